/* mocapctl replay CAPTURE with the pose model: decode -> filter -> calibrate -> model -> drift
 * correction, written as BVH (--out), JSON lines (--json) or CSV (--pose-csv), and measured
 * against a pose truth (--truth, --metrics-json). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <io.h>
#define isatty _isatty
#else
#include <unistd.h>
#endif

#include "bvh_writer.h"
#include "calibration_report.h"
#include "cli_args.h"
#include "commands.h"
#include "interrupt.h"
#include "output_file.h"
#include "platform.h"
#include "pose_files.h"
#include "pose_metrics.h"
#include "pose_model.h"
#include "pose_truth.h"
#include "replay_session.h"
#include "report.h"
#include "sensor_set.h"

#define POSE_DRAIN 256

/* Prints a calibration step's result once it has one; returns 1 when it has. */
static int report_step_once(mocap_session *session, int step, const char *label, int *done, int *failed)
{
    if (*done) return 1;
    mocap_calibration_report rep;
    if (mocap_calibration_get_step_report(session, step, &rep) != MOCAP_OK) return 0;
    if (rep.state != MOCAP_CALIBRATION_ACCEPTED && rep.state != MOCAP_CALIBRATION_REFUSED) return 0;
    printf("  %s: %s\n", label, rep.state == MOCAP_CALIBRATION_ACCEPTED ? "accepted" : "REFUSED");
    calibration_print_quality(&rep);
    if (rep.state != MOCAP_CALIBRATION_ACCEPTED) {
        printf("    reason: %s\n", rep.reason);
        *failed = 1;
    }
    *done = 1;
    return 1;
}

/* Progress on stderr while a long replay runs: a rewritten line on a terminal, a line per tenth
 * of the capture otherwise (a log). */
typedef struct progress {
    long total_bytes;
    int tty;
    int64_t start_ns, last_ns;
    int last_decile, shown;
} progress;

static void progress_update(progress *pr, mocap_session *session, const char *capture,
                            uint64_t poses)
{
    int64_t now = mocap_monotonic_ns();
    if (pr->total_bytes <= 0 || now - pr->last_ns <= 500000000LL || now - pr->start_ns <= 1000000000LL)
        return;
    mocap_session_stats stats;
    mocap_session_get_stats(session, &stats);
    double frac = (double)stats.bytes_received / (double)pr->total_bytes;
    if (frac > 1) frac = 1;
    int decile = (int)(frac * 10);
    if (pr->tty) {
        fprintf(stderr, "\r  %3.0f%% of %s, %llu poses ", 100 * frac, capture,
                (unsigned long long)poses);
        pr->shown = 1;
    } else if (decile > pr->last_decile) {
        fprintf(stderr, "  %d%% of %s, %llu poses\n", decile * 10, capture,
                (unsigned long long)poses);
        pr->last_decile = decile;
    }
    pr->last_ns = now;
}

int cmd_replay_pose(int argc, char **argv)
{
    const char *capture = argv[0];
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
    const char *model_arg = cli_value(argc, argv, "--model");
    const char *out_path = cli_value(argc, argv, "--out");
    const char *json_path = cli_value(argc, argv, "--json");
    const char *csv_path = cli_value(argc, argv, "--pose-csv");
    const char *truth_path = cli_value(argc, argv, "--truth");
    const char *metrics_path = cli_value(argc, argv, "--metrics-json");
    const char *cal_path = cli_value(argc, argv, "--calibration");
    const char *save_cal = cli_value(argc, argv, "--save-calibration");
    const char *prelude = cli_value(argc, argv, "--prelude");
    const char *order = cli_value(argc, argv, "--bvh-order");
    int rc = 1;
    mocap_model *model = NULL;
    mocap_solver *solver = NULL;
    mocap_session *session = NULL;
    bvh_writer *bvh = NULL;
    FILE *json = NULL, *csv = NULL;
    pose_truth truth = {0};
    pose_metrics *metrics = NULL;
    mocap_pose *poses = NULL;
    mocap_model_info info;
    mocap_status s;

    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    if (sensor_set_from_args(argc, argv, &cfg) != 0) return 2;
    /* The solver consumes the frames, at the model's rate. */
    cli_refuse_options(argc, argv, "--csv", "(sensor frames) is not written with the pose model; use --pose-csv");
    cli_refuse_options(argc, argv, "--rate", "does not apply with the pose model: frames come at its rate");
    if (truth_path) {
        int cols = csv_first_row_columns(truth_path);
        if (cols < 0) {
            fprintf(stderr, "mocapctl: cannot open truth file %s\n", truth_path);
            return 1;
        }
        if (cols != POSE_TRUTH_COLUMNS) {
            fprintf(stderr, "mocapctl: %s is not a pose truth (%d columns, expected %d: "
                    "`python3 -m training synth-capture` writes CAPTURE.truth.csv); a sensor "
                    "truth works without --model/--out/--json/--pose-csv\n",
                    truth_path, cols, POSE_TRUTH_COLUMNS);
            return 1;
        }
        if (pose_truth_load(truth_path, &truth) != 0) return 1;
    }
    if (metrics_path && !truth_path) {
        fprintf(stderr, "mocapctl: --metrics-json needs --truth (the accuracy is measured against it)\n");
        return 2;
    }
    bvh_rotation_order bvh_order = BVH_ORDER_ZXY;
    if (order && strcmp(order, "xyz") == 0) bvh_order = BVH_ORDER_XYZ;
    else if (order && strcmp(order, "zxy") != 0) {
        fprintf(stderr, "mocapctl: --bvh-order must be zxy or xyz\n");
        goto done;
    }
    if (pose_model_open(model_arg, &model, &info) != 0) goto done;
    metrics = (pose_metrics *)calloc(1, sizeof *metrics);
    poses = (mocap_pose *)malloc(POSE_DRAIN * sizeof *poses);
    if (!metrics || !poses) goto done;
    if (truth.rows && pose_metrics_init(metrics, &info) != 0) goto done;

    if (out_path) {
        bvh_skeleton sk;
        s = bvh_skeleton_from_model_info(&info, &sk);
        if (s == MOCAP_OK) s = bvh_writer_open(out_path, &sk, 1.0 / info.frame_rate, bvh_order, &bvh);
        if (s != MOCAP_OK) {
            rc = report_failure(s, "writing BVH");
            goto done;
        }
        bvh_writer_set_flush_every(bvh, (uint32_t)(info.frame_rate > 1 ? info.frame_rate : 1));
    }
    if (json_path && !(json = mocap_fopen(json_path, "w"))) {
        fprintf(stderr, "mocapctl: cannot write %s\n", json_path);
        goto done;
    }
    if (csv_path) {
        if (!(csv = mocap_fopen(csv_path, "w"))) {
            fprintf(stderr, "mocapctl: cannot write %s\n", csv_path);
            goto done;
        }
        pose_write_csv_header(csv, &info);
    }

    sensor_set_apply_model(&cfg, &info);
    cfg.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(cfg.path, sizeof cfg.path, "%s", capture);
    cfg.replay_realtime = cli_flag(argc, argv, "--realtime");
    cfg.output_rate_hz = info.frame_rate;
    if (replay_session_open(capture, &cfg, prelude, cal_path, &session) != 0) goto done;
    int32_t character = -1;
    s = mocap_solver_open(model, &solver_config, &solver);
    if (s == MOCAP_OK) s = mocap_solver_set_smoothing_delay(solver, cli_smoothing_delay(argc, argv));
    if (s == MOCAP_OK) s = mocap_solver_set_foot_pinning(solver, foot_pin);
    if (s == MOCAP_OK) s = mocap_solver_set_pose_limits(solver, pose_limits);
    if (s == MOCAP_OK) s = mocap_solver_set_chest_follow(solver, chest_follow);
    if (s == MOCAP_OK) s = mocap_solver_add_character(solver, session, &character);
    if (s == MOCAP_OK && apply_height(solver, character, height) != 0) goto done;
    if (s == MOCAP_OK) s = mocap_solver_start(solver);
    if (s == MOCAP_OK) s = mocap_session_start(session);
    if (s != MOCAP_OK) {
        rc = report_failure(s, "starting the solver");
        goto done;
    }
    printf("replay %s\n", capture);

    progress pr = {file_size(capture), isatty(2), mocap_monotonic_ns(), 0, 0, 0};
    pr.last_ns = pr.start_ns;
    int heading_done = cal_path != NULL, tpose_done = cal_path != NULL, cal_failed = 0;
    uint64_t written = 0;
    double first_t = 0, last_t = 0;
    for (;;) {
        uint32_t n = 0;
        s = mocap_solver_drain(solver, character, poses, POSE_DRAIN, &n);
        for (uint32_t i = 0; i < n; ++i) {
            const mocap_pose *p = &poses[i];
            if (written == 0) first_t = p->time_s;
            last_t = p->time_s;
            written++;
            if (bvh && bvh_writer_append_pose(bvh, p) != MOCAP_OK) {
                rc = report_failure(MOCAP_ERR_IO, "writing BVH");
                goto done;
            }
            if (json) pose_write_json_line(json, p);
            if (csv) pose_write_csv_line(csv, p);
            pose_truth_row tr;
            if (truth.rows && pose_truth_at(&truth, p->time_s, &tr) == 0)
                pose_metrics_add(metrics, p, &tr);
        }
        report_step_once(session, MOCAP_CALIBRATION_HEADING, "heading step", &heading_done, &cal_failed);
        if (heading_done) report_step_once(session, MOCAP_CALIBRATION_TPOSE, "T-pose step", &tpose_done, &cal_failed);
        if (s == MOCAP_ERR_END_OF_STREAM || mocapctl_interrupted) break;
        if (s != MOCAP_OK && s != MOCAP_ERR_NO_DATA) {
            rc = report_failure(s, "solving");
            goto done;
        }
        progress_update(&pr, session, capture, written);
        if (n == 0) mocap_sleep_ms(1);
    }
    if (pr.shown) fprintf(stderr, "\r%60s\r", "");
    if (!heading_done || !tpose_done)
        printf("  calibration: the capture ended before %s finished\n",
               !heading_done ? "the heading step" : "the T-pose step");
    const double wall = (double)(mocap_monotonic_ns() - pr.start_ns) * 1e-9;

    if (save_cal && calibration_save_reported(session, save_cal) != 0) goto done; /* rc is still 1 */
    mocap_session_stats stats;
    mocap_session_get_stats(session, &stats);
    printf("  %llu bytes, %llu HiPNUC frames, %llu CRC failures, %llu samples (%llu rejected), "
           "%llu output frames\n",
           (unsigned long long)stats.bytes_received, (unsigned long long)stats.frames_decoded,
           (unsigned long long)stats.crc_failures, (unsigned long long)stats.samples_decoded,
           (unsigned long long)stats.samples_rejected, (unsigned long long)stats.frames_emitted);
    printf("  %llu poses at %.0f Hz over %.2f s (%.0f poses/s of wall time)\n",
           (unsigned long long)written, info.frame_rate, written ? last_t - first_t : 0.0,
           wall > 0 ? (double)written / wall : 0.0);
    if (bvh) {
        s = bvh_writer_close(bvh);
        bvh = NULL;
        if (s != MOCAP_OK) {
            rc = report_failure(s, "writing BVH");
            goto done;
        }
        printf("  wrote %s (BVH, SMPL-24 skeleton, metres, %s Euler, %llu frames at %.0f Hz)\n",
               out_path, bvh_order == BVH_ORDER_XYZ ? "XYZ" : "ZXY", (unsigned long long)written,
               info.frame_rate);
    }
    if (json && output_close(&json, json_path)) {
        rc = 1;
        goto done;
    }
    if (json_path) printf("  wrote %s (one JSON object per pose)\n", json_path);
    if (csv && output_close(&csv, csv_path)) {
        rc = 1;
        goto done;
    }
    if (csv_path) printf("  wrote %s (one CSV line per pose)\n", csv_path);
    if (truth.rows) pose_metrics_print(metrics, truth_path);
    if (metrics_path && pose_metrics_write_json(metrics, truth_path, metrics_path) != 0) goto done;
    if (metrics_path) printf("  wrote %s (the accuracy figures as JSON)\n", metrics_path);
    rc = (cal_failed || written == 0) ? 1 : 0;
    if (written == 0) fprintf(stderr, "mocapctl: no pose was solved (calibration %s)\n",
                              cal_failed ? "refused" : "missing");
    if (report_replay_ended_early(session)) rc = 1;
    report_capture_damage(session, capture);
    report_dropped(session, solver, character, "the replay",
                   "a replay without --realtime waits instead of dropping");
    if (report_inference_failures(solver)) rc = 1;
done:
    /* Solver first (it consumes the session), then the session, then the model. */
    if (solver) mocap_solver_close(solver);
    if (session) mocap_session_close(session);
    if (model) mocap_model_close(model);
    if (bvh) bvh_writer_close(bvh);
    if (json) fclose(json);
    if (csv) fclose(csv);
    if (metrics) {
        pose_metrics_free(metrics);
        free(metrics);
    }
    free(poses);
    pose_truth_free(&truth);
    return rc;
}
