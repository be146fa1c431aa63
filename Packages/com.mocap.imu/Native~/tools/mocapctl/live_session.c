/* Live serial sessions (live_session.h). */
#include "live_session.h"

#include <stdio.h>

#include "calibration_report.h"
#include "cli_args.h"
#include "commands.h"
#include "interrupt.h"
#include "platform.h"
#include "report.h"
#include "sensor_set.h"

#define NO_FRAMES_LIMIT_S 5.0

int live_session_open(const char *command, int argc, char **argv, const char *record_path,
                      float rate_hz, const mocap_model_info *model, mocap_session **out)
{
    const char *port = cli_value(argc, argv, "--port");
    if (!port) return mocapctl_usage_error(command);
    if (report_path_too_long(port, "port") ||
        (record_path && report_path_too_long(record_path, "recording")))
        return 2;
    const char *baud = cli_value(argc, argv, "--baud");
    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    if (sensor_set_from_args(argc, argv, &cfg) != 0) return 2;
    if (model) sensor_set_apply_model(&cfg, model);
    cfg.source_kind = MOCAP_SOURCE_SERIAL;
    snprintf(cfg.path, sizeof cfg.path, "%s", port);
    if (baud) cfg.baud = (uint32_t)cli_integer(argc, argv, "--baud", 0, 50, 16000000);
    if (record_path) snprintf(cfg.capture_path, sizeof cfg.capture_path, "%s", record_path);
    if (rate_hz > 0) cfg.output_rate_hz = rate_hz;
    mocap_status s = mocap_session_open(&cfg, out);
    if (s != MOCAP_OK) return report_failure(s, "opening the receiver");
    char described[512];
    sensor_set_describe(&cfg, described, sizeof described);
    printf("%u sensors (segment=node, ? optional): %s\n", (unsigned)cfg.sensor_count, described);
    s = mocap_session_start(*out);
    if (s != MOCAP_OK) {
        mocap_session_close(*out);
        *out = NULL; /* callers close what they were handed on their own way out */
        return report_failure(s, "starting");
    }
    return 0;
}

static void print_status_line(mocap_session *session, const mocap_frame *f)
{
    mocap_session_stats stats;
    mocap_session_get_stats(session, &stats);
    static const char *states[] = {"closed", "connected", "DISCONNECTED", "ended"};
    int cs = stats.connection_state >= 0 && stats.connection_state <= 3 ? stats.connection_state : 0;
    printf("\r%-12s frames %-7llu crc-fail %-5llu sensors ", states[cs],
           (unsigned long long)stats.frames_emitted, (unsigned long long)stats.crc_failures);
    static const char STATE_CHARS[] = "ohS."; /* by mocap_sensor_state */
    for (uint32_t s = 0; f && s < f->sensor_count && s < MOCAP_MAX_SENSORS; ++s) {
        const int32_t state = f->sensors[s].state;
        putchar(state >= 0 && state <= MOCAP_SENSOR_ABSENT ? STATE_CHARS[state] : '?');
    }
    if (cs == MOCAP_CONNECTION_DISCONNECTED) printf("  %s", stats.last_error);
    printf("    ");
    fflush(stdout);
}

void live_session_show_status(mocap_session *session, double limit_s)
{
    int64_t start = mocap_monotonic_ns();
    mocap_frame frame;
    int have = 0, named = 0;
    while (!mocapctl_interrupted && (double)(mocap_monotonic_ns() - start) * 1e-9 < limit_s) {
        if (mocap_session_poll_latest(session, &frame) == MOCAP_OK) have = 1;
        if (have && !named) {
            /* The legend of the status line's sensor column, once the first frame says the set. */
            printf("\rsensors:");
            for (uint32_t s = 0; s < frame.sensor_count && s < MOCAP_MAX_SENSORS; ++s)
                printf(" %s(%u)", mocap_segment_name(frame.sensors[s].segment),
                       (unsigned)frame.sensors[s].node_id);
            printf("  (o fresh, h held, S silent, . absent)\n");
            named = 1;
        }
        print_status_line(session, have ? &frame : NULL);
        mocap_sleep_ms(100);
    }
    printf("\n");
}

int live_session_guided_step(mocap_session *session, int step, const char *instruction,
                             float seconds)
{
    printf("\n%s\n", instruction);
    for (int i = 3; i > 0 && !mocapctl_interrupted; --i) {
        printf("  starting in %d...\n", i);
        mocap_sleep_ms(1000);
    }
    mocap_status s = mocap_calibration_schedule(session, step, -1.0, seconds);
    if (s != MOCAP_OK) return report_failure(s, "scheduling calibration");
    mocap_calibration_report rep;
    mocap_frame frame;
    const int64_t waiting_since = mocap_monotonic_ns();
    int have_frame = 0;
    for (;;) {
        if (mocap_session_poll_latest(session, &frame) == MOCAP_OK) have_frame = 1;
        mocap_calibration_get_report(session, &rep);
        if (rep.state == MOCAP_CALIBRATION_ACCEPTED || rep.state == MOCAP_CALIBRATION_REFUSED) break;
        if (!have_frame && (double)(mocap_monotonic_ns() - waiting_since) * 1e-9 > NO_FRAMES_LIMIT_S) {
            mocap_session_stats stats;
            mocap_session_get_stats(session, &stats);
            printf("\n");
            fprintf(stderr, "mocapctl: no frame from the receiver in %.0f s (%llu bytes received%s%s): "
                            "check the port, the baud rate (--baud) and that the sensors are on\n",
                    NO_FRAMES_LIMIT_S, (unsigned long long)stats.bytes_received,
                    stats.last_error[0] ? "; " : "", stats.last_error);
            return GUIDED_STEP_NO_FRAMES;
        }
        printf("\r  hold still: %.1f s  ", rep.seconds_remaining);
        fflush(stdout);
        if (mocapctl_interrupted) return 1;
        mocap_sleep_ms(100);
    }
    printf("\r  %s\n", rep.state == MOCAP_CALIBRATION_ACCEPTED ? "accepted" : "REFUSED");
    calibration_print_quality(&rep);
    if (rep.state == MOCAP_CALIBRATION_REFUSED) {
        printf("  reason: %s\n", rep.reason);
        return 1;
    }
    return 0;
}
