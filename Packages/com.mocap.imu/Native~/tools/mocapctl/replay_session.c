/* Replay sessions with their calibration arranged (replay_session.h). */
#include "replay_session.h"

#include <stdio.h>

#include "capture_file.h"
#include "report.h"

/* Session time of the capture's first record, where the prelude's windows are counted from. */
static int first_capture_time(const char *path, double *t0)
{
    capture_reader *r = NULL;
    mocap_status st = capture_reader_open(path, &r);
    if (st != MOCAP_OK) return report_failure(st, "opening capture");
    int64_t ns;
    const uint8_t *data;
    size_t len;
    st = capture_reader_next(r, &ns, &data, &len);
    capture_reader_close(r);
    if (st != MOCAP_OK) {
        fprintf(stderr, "mocapctl: capture %s holds no data\n", path);
        return 1;
    }
    *t0 = (double)ns * 1e-9;
    return 0;
}

int replay_session_open(const char *capture, mocap_session_config *cfg, const char *prelude,
                        const char *calibration_path, mocap_session **out)
{
    double t0 = 0;
    if (report_path_too_long(capture, "capture")) return 1;
    if (first_capture_time(capture, &t0) != 0) return 1;
    double heading_s = 3.0, strap_s = 2.0, tpose_s = 3.0;
    if (prelude && sscanf(prelude, "%lf,%lf,%lf", &heading_s, &strap_s, &tpose_s) != 3) {
        fprintf(stderr, "mocapctl: --prelude wants HEADING,STRAP,TPOSE seconds\n");
        return 1;
    }
    mocap_status s = mocap_session_open(cfg, out);
    if (s != MOCAP_OK) return report_failure(s, "opening replay");
    if (calibration_path) {
        mocap_calibration cal;
        s = mocap_calibration_load(calibration_path, &cal);
        if (s == MOCAP_OK) s = mocap_calibration_set(*out, &cal);
        if (s != MOCAP_OK) return report_failure(s, "loading calibration");
        return 0;
    }
    s = mocap_calibration_schedule(*out, MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                   (float)(heading_s - 1.0));
    if (s == MOCAP_OK)
        s = mocap_calibration_schedule(*out, MOCAP_CALIBRATION_TPOSE,
                                       t0 + heading_s + strap_s + 0.5, (float)(tpose_s - 1.0));
    if (s != MOCAP_OK) return report_failure(s, "scheduling calibration");
    return 0;
}
