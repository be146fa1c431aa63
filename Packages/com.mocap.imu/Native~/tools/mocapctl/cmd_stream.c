/* mocapctl stream: solved poses to VMC receivers (OSC over UDP), character i to the i-th --vmc;
 * the characters come from replays (--replay, one per character) or one live port (--port). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "cli_args.h"
#include "commands.h"
#include "interrupt.h"
#include "live_session.h"
#include "platform.h"
#include "pose_model.h"
#include "replay_session.h"
#include "report.h"
#include "sensor_set.h"

#define STREAM_MAX 16
#define POSE_DRAIN 256

int cmd_stream(int argc, char **argv)
{
    const char *dests[STREAM_MAX], *replays[STREAM_MAX];
    int ndest = cli_values(argc, argv, "--vmc", dests, STREAM_MAX);
    int nrep = cli_values(argc, argv, "--replay", replays, STREAM_MAX);
    const char *port = cli_value(argc, argv, "--port");
    const char *rate = cli_value(argc, argv, "--rate");
    /* Read before anything is opened: a bad value must not leave an empty capture behind. */
    const double limit = cli_number(argc, argv, "--seconds", 1e30, 0.001, 1e30);
    const char *speed = cli_value(argc, argv, "--speed");
    const int fast = cli_flag(argc, argv, "--fast");
    const double pace = speed ? cli_number(argc, argv, "--speed", 1.0, 0.01, 1000.0) : 1.0;
    const char *prelude = cli_value(argc, argv, "--prelude");
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
    mocap_session_config sensor_check;
    mocap_config_defaults(&sensor_check);
    if (sensor_set_from_args(argc, argv, &sensor_check) != 0) return 2; /* before any socket */
    if (ndest < 0 || nrep < 0) {
        fprintf(stderr, "mocapctl: at most %d --vmc and --replay\n", STREAM_MAX);
        return 2;
    }
    if (ndest == 0 || (nrep == 0) == (port == NULL)) {
        fprintf(stderr, "mocapctl stream: give --vmc HOST:PORT (e.g. 127.0.0.1:39539) and either "
                        "--replay CAPTURE or --port DEV\n");
        return mocapctl_usage_error("stream");
    }
    if (fast && (speed || cli_flag(argc, argv, "--realtime"))) {
        fprintf(stderr, "mocapctl stream: --fast sends as fast as the model solves; it cannot be "
                        "combined with --realtime or --speed\n");
        return 2;
    }
    if (port)
        cli_refuse_options(argc, argv, "--speed --realtime --fast --prelude", "applies to --replay only");
    else
        cli_refuse_options(argc, argv, "--baud", "applies to --port only");
    const int characters = port ? 1 : nrep;
    if (ndest != characters) {
        fprintf(stderr, "mocapctl stream: %d character(s) but %d --vmc destination(s): character i "
                        "goes to the i-th --vmc\n", characters, ndest);
        return 2;
    }
    mocap_vmc_options vopt;
    mocap_vmc_options_defaults(&vopt);
    if (rate) vopt.max_rate_hz = (float)cli_number(argc, argv, "--rate", 60.0, 0.1, 1000.0);
    vopt.allow_remote = cli_flag(argc, argv, "--allow-remote");

    int rc = 1;
    mocap_model *model = NULL;
    mocap_model_info info;
    mocap_solver *solver = NULL;
    mocap_session *sessions[STREAM_MAX] = {0};
    mocap_vmc *vmc[STREAM_MAX] = {0};
    int32_t ids[STREAM_MAX];
    int ended[STREAM_MAX] = {0};
    mocap_pose *poses = NULL;
    mocap_status s;

    /* Destinations first: a bad one fails before anything is loaded. */
    for (int i = 0; i < ndest; ++i) {
        s = mocap_vmc_open(dests[i], &vopt, &vmc[i]);
        if (s != MOCAP_OK) {
            rc = report_failure(s, "VMC destination");
            goto done;
        }
    }
    if (pose_model_open(cli_value(argc, argv, "--model"), &model, &info) != 0) goto done;
    if (height_supported(model, height) != 0) goto done; /* before a port's calibration */
    poses = (mocap_pose *)malloc((size_t)characters * POSE_DRAIN * sizeof *poses);
    if (!poses) goto done;

    if (port) {
        if (live_session_open("stream", argc, argv, NULL, info.frame_rate, &info, &sessions[0]) != 0) goto done;
        int cal = live_session_guided_step(sessions[0], MOCAP_CALIBRATION_HEADING,
                                           "Heading step: lay all the sensors still on a flat "
                                           "surface, X axis (the arrow) pointing where you will "
                                           "face, Z up.", 3.0f);
        if (cal == 0)
            cal = live_session_guided_step(sessions[0], MOCAP_CALIBRATION_TPOSE,
                                           "T-pose step: strap the sensors on, face the same way, "
                                           "arms straight out to the sides, stand still.", 3.0f);
        if (cal != 0) goto done;
    } else {
        for (int i = 0; i < nrep; ++i) {
            mocap_session_config cfg;
            mocap_config_defaults(&cfg);
            if (sensor_set_from_args(argc, argv, &cfg) != 0) {
                rc = 2;
                goto done;
            }
            sensor_set_apply_model(&cfg, &info);
            cfg.source_kind = MOCAP_SOURCE_REPLAY;
            snprintf(cfg.path, sizeof cfg.path, "%s", replays[i]);
            /* The session runs ahead (a fast replay waits when its queues are full, so nothing
             * is lost); the send loop below paces the poses by their own time stamps. */
            cfg.replay_realtime = 0;
            cfg.output_rate_hz = info.frame_rate;
            if (replay_session_open(replays[i], &cfg, prelude, NULL, &sessions[i]) != 0) goto done;
        }
    }
    s = mocap_solver_open(model, &solver_config, &solver);
    if (s == MOCAP_OK) s = mocap_solver_set_smoothing_delay(solver, cli_smoothing_delay(argc, argv));
    if (s == MOCAP_OK) s = mocap_solver_set_foot_pinning(solver, foot_pin);
    if (s == MOCAP_OK) s = mocap_solver_set_pose_limits(solver, pose_limits);
    if (s == MOCAP_OK) s = mocap_solver_set_chest_follow(solver, chest_follow);
    for (int i = 0; s == MOCAP_OK && i < characters; ++i)
        s = mocap_solver_add_character(solver, sessions[i], &ids[i]);
    for (int i = 0; s == MOCAP_OK && i < characters; ++i)
        if (apply_height(solver, ids[i], height) != 0) goto done;
    if (s == MOCAP_OK) s = mocap_solver_start(solver);
    for (int i = 0; !port && s == MOCAP_OK && i < characters; ++i) s = mocap_session_start(sessions[i]);
    if (s != MOCAP_OK) {
        rc = report_failure(s, "starting the solver");
        goto done;
    }
    for (int i = 0; i < characters; ++i)
        printf("character %d (%s) -> VMC %s, at most %g bundles/s\n", i, port ? port : replays[i],
               dests[i], (double)vopt.max_rate_hz);
    fflush(stdout);

    /* A replay is sent at its own pace: pose k of a character leaves at the time its frame was
     * recorded (relative to the character's first pose, divided by --speed), however unevenly
     * the engine solved them, so a receiver sees one bundle every 1/rate s. Live poses and
     * --fast leave as soon as they are solved. */
    const int paced = !port && !fast;
    const int64_t start = mocap_monotonic_ns();
    uint64_t send_errors = 0;
    int running = characters;
    uint32_t pending[STREAM_MAX] = {0}, next[STREAM_MAX] = {0};
    double first_time[STREAM_MAX];
    int have_first[STREAM_MAX] = {0};
    while (running > 0 && !mocapctl_interrupted &&
           (double)(mocap_monotonic_ns() - start) * 1e-9 < limit) {
        int64_t earliest_due = INT64_MAX;
        int progressed = 0;
        for (int i = 0; i < characters; ++i) {
            if (ended[i]) continue;
            mocap_pose *mine = poses + (size_t)i * POSE_DRAIN;
            if (next[i] == pending[i]) {
                uint32_t n = 0;
                s = mocap_solver_drain(solver, ids[i], mine, POSE_DRAIN, &n);
                if (s == MOCAP_ERR_END_OF_STREAM) {
                    ended[i] = 1;
                    running--;
                    continue;
                }
                if (s != MOCAP_OK && s != MOCAP_ERR_NO_DATA) {
                    rc = report_failure(s, "solving");
                    goto done;
                }
                pending[i] = n;
                next[i] = 0;
                if (n > 0 && !have_first[i]) {
                    first_time[i] = mine[0].time_s;
                    have_first[i] = 1;
                }
            }
            while (next[i] < pending[i]) {
                const mocap_pose *pose = &mine[next[i]];
                if (paced) {
                    int64_t due = start + (int64_t)((pose->time_s - first_time[i]) / pace * 1e9);
                    if (mocap_monotonic_ns() < due) {
                        if (due < earliest_due) earliest_due = due;
                        break;
                    }
                }
                mocap_status vs = mocap_vmc_send_pose(vmc[i], &info, pose);
                if (vs != MOCAP_OK && vs != MOCAP_ERR_NO_DATA && send_errors++ < 5)
                    fprintf(stderr, "mocapctl: %s\n", mocap_last_error());
                next[i]++;
                progressed = 1;
            }
        }
        if (progressed) continue;
        if (earliest_due != INT64_MAX) {
            int64_t wait_ns = earliest_due - mocap_monotonic_ns();
            /* Whole milliseconds: a pose leaves within about 1 ms of its time (no busy wait). */
            mocap_sleep_ms(wait_ns > 1000000 ? (int)(wait_ns / 1000000) : 1);
        } else {
            mocap_sleep_ms(1);
        }
    }
    rc = 0;
    for (int i = 0; i < characters; ++i) {
        mocap_vmc_stats st;
        mocap_vmc_get_stats(vmc[i], &st);
        printf("character %d -> %s: %llu poses, %llu bundles sent (%u bones each, %u bytes), "
               "%llu skipped by the rate cap, %llu send failures\n",
               i, dests[i], (unsigned long long)st.poses, (unsigned long long)st.bundles_sent,
               st.bones_per_bundle, st.last_bundle_size, (unsigned long long)st.skipped_rate,
               (unsigned long long)st.send_failures);
        if (st.bundles_sent == 0) {
            fprintf(stderr, "mocapctl: character %d: nothing was sent (calibration refused or the "
                            "capture ended before it finished)\n", i);
            rc = 1;
        }
    }
    if (report_inference_failures(solver)) rc = 1;
    /* A replay whose file stopped reading part way streamed less than the capture holds. */
    for (int i = 0; !port && i < nrep; ++i) {
        if (report_replay_ended_early(sessions[i])) rc = 1;
        report_capture_damage(sessions[i], replays[i]);
    }
    for (int i = 0; i < characters; ++i) {
        char what[32];
        snprintf(what, sizeof what, "character %d", i);
        report_dropped(sessions[i], solver, ids[i], what,
                       port ? "the machine could not keep up with the sensors"
                            : "a streamed replay waits instead of dropping, so this is a bug: "
                              "please report it with the capture");
    }
done:
    if (solver) mocap_solver_close(solver);
    for (int i = 0; i < STREAM_MAX; ++i) {
        if (sessions[i]) mocap_session_close(sessions[i]);
        mocap_vmc_close(vmc[i]);
    }
    if (model) mocap_model_close(model);
    free(poses);
    return rc;
}
