/* Printing and saving calibrations (calibration_report.h). */
#include "calibration_report.h"

#include <stdio.h>

#include "report.h"

void calibration_print_quality(const mocap_calibration_report *rep)
{
    for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
        const mocap_sensor_quality *q = &rep->sensors[s];
        printf("    %-12s %s  gyro %5.2f deg/s  spread %5.2f deg  |g| err %5.2f m/s^2",
               mocap_segment_name(s), q->ok ? "ok  " : "BAD ", q->gyro_rms_dps,
               q->orientation_spread_deg, q->accel_norm_error);
        /* Tilt is a check of the heading step only (sensors must lie flat). */
        if (rep->step == MOCAP_CALIBRATION_HEADING) printf("  tilt %5.1f deg", q->tilt_deg);
        printf("  %u samples\n", q->samples);
    }
}

int calibration_save_reported(mocap_session *session, const char *path)
{
    mocap_calibration cal;
    mocap_calibration_get(session, &cal);
    mocap_status s = mocap_calibration_save(&cal, path);
    if (s != MOCAP_OK) return report_failure(s, "saving calibration");
    printf("  calibration saved to %s\n", path);
    return 0;
}
