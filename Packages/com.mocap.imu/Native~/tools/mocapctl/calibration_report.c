/* Printing and saving calibrations (calibration_report.h). */
#include "calibration_report.h"

#include <stdio.h>

#include "report.h"

void calibration_print_quality(const mocap_calibration_report *rep)
{
    for (uint32_t s = 0; s < rep->sensor_count && s < MOCAP_MAX_SENSORS; ++s) {
        const mocap_sensor_quality *q = &rep->sensors[s];
        const char *name = mocap_segment_name(q->segment);
        if (q->left_out) {
            printf("    %-12s left out (optional, sent nothing)\n", name ? name : "?");
            continue;
        }
        printf("    %-12s %s  gyro %5.2f deg/s  spread %5.2f deg  |g| err %5.2f m/s^2",
               name ? name : "?", q->ok ? "ok  " : "BAD ", q->gyro_rms_dps,
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
