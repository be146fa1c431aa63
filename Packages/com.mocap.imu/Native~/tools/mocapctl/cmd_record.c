/* mocapctl record --port DEV --out CAPTURE: the port's bytes into a capture file, with the live
 * status line, until Ctrl-C or --seconds. */
#include <stdio.h>

#include "cli_args.h"
#include "commands.h"
#include "live_session.h"
#include "sensor_set.h"

int cmd_record(int argc, char **argv)
{
    const char *out = cli_value(argc, argv, "--out");
    /* Read before anything is opened: a bad value must not leave an empty capture behind. */
    const double limit = cli_number(argc, argv, "--seconds", 1e30, 0.001, 1e30);
    if (!out) return mocapctl_usage_error("record");
    mocap_session_config sensor_check;
    mocap_config_defaults(&sensor_check);
    if (sensor_set_from_args(argc, argv, &sensor_check) != 0) return 2; /* before the capture */
    static const char *const record_outputs[] = {"--out", NULL};
    cli_refuse_overwriting(cli_value(argc, argv, "--port"), "serial port", argc, argv, record_outputs);
    mocap_session *session = NULL;
    if (live_session_open("record", argc, argv, out, 0.0f, NULL, &session) != 0) return 1;
    printf("recording to %s; Ctrl-C to stop\n", out);
    live_session_show_status(session, limit);
    /* Stop first: the final flush and the close are where a full disk often shows. */
    const mocap_status stopped = mocap_session_stop(session);
    char why[256] = "";
    if (stopped != MOCAP_OK) snprintf(why, sizeof why, "%s", mocap_last_error());
    mocap_session_stats stats;
    mocap_session_get_stats(session, &stats);
    mocap_session_close(session);
    printf("\nrecorded %llu bytes from the port (%llu bytes on disk)\n",
           (unsigned long long)stats.bytes_received,
           (unsigned long long)stats.capture_bytes_written);
    if (stopped != MOCAP_OK) {
        fprintf(stderr, "mocapctl record: the recording failed (%s): %s\n",
                mocap_status_name(stopped), why);
        return 1;
    }
    return 0;
}
