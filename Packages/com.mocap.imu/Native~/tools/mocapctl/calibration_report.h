/* Calibration results as mocapctl's commands print them, and --save-calibration. */
#ifndef MOCAPCTL_CALIBRATION_REPORT_H
#define MOCAPCTL_CALIBRATION_REPORT_H

#include "mocap_imu.h"

/* One line per sensor of the report, named by its segment: ok/BAD, gyro, spread, |g| error (tilt
 * for the heading step), samples; or that an optional sensor was left out. */
void calibration_print_quality(const mocap_calibration_report *report);

/* The session's calibration to `path`; 0, or 1 after printing why not. */
int calibration_save_reported(mocap_session *session, const char *path);

#endif
