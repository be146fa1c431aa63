/* mocapctl live --port DEV: the guided calibration on real sensors, then a live status line, or
 * with the pose model (--model, --pose) the solver's pose status; --record keeps the bytes. */
#include <stdio.h>

#include "cli_args.h"
#include "commands.h"
#include "interrupt.h"
#include "live_session.h"
#include "platform.h"
#include "pose_model.h"
#include "report.h"
#include "sensor_set.h"

#define LIVE_POSE_DRAIN 64

/* After calibration with the model: the solver consumes the session; prints the pose status
 * (fps, root position, foot contacts, flags) ten times a second. 0, or 1 when inference failed. */
static int show_poses_until(mocap_session *session, mocap_model *model,
                            const mocap_solver_config *config, int32_t smoothing_delay, float foot_pin,
                            float pose_limits, float chest_follow, float height_m, double limit_s)
{
    mocap_solver *solver = NULL;
    int32_t id = -1;
    mocap_status s = mocap_solver_open(model, config, &solver);
    if (s == MOCAP_OK) s = mocap_solver_set_smoothing_delay(solver, smoothing_delay);
    if (s == MOCAP_OK) s = mocap_solver_set_foot_pinning(solver, foot_pin);
    if (s == MOCAP_OK) s = mocap_solver_set_pose_limits(solver, pose_limits);
    if (s == MOCAP_OK) s = mocap_solver_set_chest_follow(solver, chest_follow);
    if (s == MOCAP_OK) s = mocap_solver_add_character(solver, session, &id);
    if (s == MOCAP_OK && apply_height(solver, id, height_m) != 0) {
        mocap_solver_close(solver);
        return 1;
    }
    if (s == MOCAP_OK) s = mocap_solver_start(solver);
    if (s != MOCAP_OK) {
        mocap_solver_close(solver);
        return report_failure(s, "starting the solver");
    }
    static mocap_pose poses[LIVE_POSE_DRAIN];
    mocap_pose last;
    int have = 0;
    uint64_t count = 0, window_count = 0;
    int64_t start = mocap_monotonic_ns(), window_start = start, last_print = 0;
    double fps = 0;
    while (!mocapctl_interrupted && (double)(mocap_monotonic_ns() - start) * 1e-9 < limit_s) {
        uint32_t n = 0;
        mocap_solver_drain(solver, id, poses, LIVE_POSE_DRAIN, &n);
        if (n) {
            last = poses[n - 1];
            have = 1;
            count += n;
            window_count += n;
        }
        int64_t now = mocap_monotonic_ns();
        if (now - window_start >= 1000000000LL) {
            fps = (double)window_count / ((double)(now - window_start) * 1e-9);
            window_count = 0;
            window_start = now;
        }
        if (now - last_print < 100000000LL) {
            mocap_sleep_ms(16);
            continue;
        }
        last_print = now;
        mocap_session_stats stats;
        mocap_session_get_stats(session, &stats);
        if (have) {
            printf("\rpose %-7llu %5.1f fps  root (%6.2f %5.2f %6.2f) m  feet %c%c  %s%s   ",
                   (unsigned long long)count, fps, last.root_position[0], last.root_position[1],
                   last.root_position[2], (last.flags & MOCAP_POSE_CONTACT_LEFT) ? 'L' : '.',
                   (last.flags & MOCAP_POSE_CONTACT_RIGHT) ? 'R' : '.',
                   (last.flags & MOCAP_POSE_INCOMPLETE) ? "incomplete " : "",
                   stats.connection_state == MOCAP_CONNECTION_DISCONNECTED ? stats.last_error : "");
        } else {
            printf("\rwaiting for poses (%llu frames received)   ",
                   (unsigned long long)stats.frames_emitted);
        }
        fflush(stdout);
        mocap_sleep_ms(16);
    }
    printf("\n");
    const int failed = report_inference_failures(solver);
    mocap_solver_close(solver);
    return failed;
}

int cmd_live(int argc, char **argv)
{
    mocap_session *session = NULL;
    mocap_solver_config solver_config;
    if (cli_smoothing(argc, argv, &solver_config) != 0) return 2;
    float height = 0.0f;
    if (cli_height(argc, argv, &height) != 0) return 2;
    float foot_pin = 0.0f;
    if (cli_foot_pin(argc, argv, &foot_pin) != 0) return 2;
    float pose_limits = 0.0f;
    if (cli_pose_limits(argc, argv, &pose_limits) != 0) return 2;
    float chest_follow = 0.0f;
    if (cli_chest_follow(argc, argv, &chest_follow) != 0) return 2;
    const char *record = cli_value(argc, argv, "--record");
    static const char *const live_outputs[] = {"--record", NULL};
    cli_refuse_overwriting(cli_value(argc, argv, "--port"), "serial port", argc, argv, live_outputs);
    /* Read before anything is opened: a bad value must not leave an empty capture behind. */
    const double limit = cli_number(argc, argv, "--seconds", 1e30, 0.001, 1e30);
    mocap_session_config sensor_check;
    mocap_config_defaults(&sensor_check);
    if (sensor_set_from_args(argc, argv, &sensor_check) != 0) return 2; /* before the capture */
    const int with_model = cli_value(argc, argv, "--model") != NULL || cli_flag(argc, argv, "--pose");
    if (!with_model) cli_refuse_options(argc, argv, "--smoothing --height", "applies to poses only (add --pose or --model)");
    mocap_model *model = NULL;
    mocap_model_info info;
    /* The model first: the session's output rate is the model's frame rate. */
    if (with_model && pose_model_open(cli_value(argc, argv, "--model"), &model, &info) != 0) return 1;
    if (model && height_supported(model, height) != 0) { /* before the calibration, not after */
        mocap_model_close(model);
        return 1;
    }
    if (live_session_open("live", argc, argv, record, model ? info.frame_rate : 0.0f,
                          model ? &info : NULL, &session) != 0) {
        mocap_model_close(model);
        return 1;
    }
    int rc = 0;
    for (int attempt = 0; attempt < 3; ++attempt) {
        rc = live_session_guided_step(session, MOCAP_CALIBRATION_HEADING,
                                      "Heading step: lay all the sensors still on a flat surface, X "
                                      "axis (the arrow) pointing where you will face, Z up.", 3.0f);
        if (rc == 0 || rc == GUIDED_STEP_NO_FRAMES || mocapctl_interrupted) break;
    }
    for (int attempt = 0; rc == 0 && attempt < 3; ++attempt) {
        rc = live_session_guided_step(session, MOCAP_CALIBRATION_TPOSE,
                                      "T-pose step: strap the sensors on (each on its segment, as "
                                      "listed above), face the same way, arms straight out to the "
                                      "sides, stand still.", 3.0f);
        if (rc == 0 || rc == GUIDED_STEP_NO_FRAMES || mocapctl_interrupted) break;
    }
    if (rc == 0) printf("\nCalibrated. Streaming; Ctrl-C to stop.\n");
    if (rc == GUIDED_STEP_NO_FRAMES) {
        rc = 1; /* nothing arrives: showing an empty status would only wait */
    } else if (rc == 0 && model) {
        rc = show_poses_until(session, model, &solver_config, cli_smoothing_delay(argc, argv), foot_pin,
                              pose_limits, chest_follow, height, limit);
    } else {
        live_session_show_status(session, limit);
    }
    /* A --record capture is complete only if the stop (last flush, close) says so. */
    const mocap_status stopped = mocap_session_stop(session);
    if (stopped != MOCAP_OK) {
        fprintf(stderr, "\nmocapctl live: the recording failed (%s): %s\n",
                mocap_status_name(stopped), mocap_last_error());
        rc = 1;
    }
    mocap_session_close(session);
    mocap_model_close(model);
    return rc;
}
