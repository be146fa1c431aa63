/* mocapctl replay CAPTURE: decode -> filter -> calibrate, a per-sensor summary and, with synth's
 * sensor truth (--truth), the bone orientation and acceleration error. With the pose model
 * (--model, a pose output or a pose truth) it is cmd_replay_pose's job instead. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calibration_report.h"
#include "cli_args.h"
#include "commands.h"
#include "interrupt.h"
#include "mocap_math.h"
#include "output_file.h"
#include "platform.h"
#include "pose_truth.h"
#include "replay_session.h"
#include "report.h"
#include "sensor_set.h"
#include "sensor_truth.h"

#define DRAIN_CAPACITY 256
#define HISTOGRAM_BINS 1800 /* 0.1 deg each */

typedef struct sensor_summary {
    uint64_t frames, fresh, held, stale;
    double angle_sum, angle_max, angle_sq;
    double acc_err_sq;
    uint64_t compared;
    uint32_t histogram[HISTOGRAM_BINS];
} sensor_summary;

static double histogram_percentile(const uint32_t *h, uint64_t n, double p)
{
    uint64_t target = (uint64_t)ceil(p * (double)n), seen = 0;
    for (int i = 0; i < HISTOGRAM_BINS; ++i) {
        seen += h[i];
        if (seen >= target && target > 0) return (i + 1) * 0.1;
    }
    return 180.0;
}

typedef struct replay_state {
    mocap_session *session;
    sensor_truth truth;
    int have_truth;
    FILE *csv;
    sensor_summary sensors[MOCAP_MAX_SENSORS]; /* config order */
    uint64_t frames;
    uint64_t calibrated_frames;
    double first_t, last_t;
    mocap_frame buffer[DRAIN_CAPACITY];
} replay_state;

static void account_frame(replay_state *st, const mocap_frame *f)
{
    if (st->frames == 0) st->first_t = f->time_s;
    st->last_t = f->time_s;
    st->frames++;
    if (f->flags & MOCAP_FRAME_CALIBRATED) st->calibrated_frames++;
    sensor_truth_row truth;
    int have = st->have_truth && (f->flags & MOCAP_FRAME_CALIBRATED) &&
               sensor_truth_at(&st->truth, f->time_s, &truth) == 0 && truth.phase == 3;
    const uint32_t sensors = f->sensor_count < MOCAP_MAX_SENSORS ? f->sensor_count : MOCAP_MAX_SENSORS;
    for (uint32_t s = 0; s < sensors; ++s) {
        const mocap_sensor_frame *sf = &f->sensors[s];
        sensor_summary *sum = &st->sensors[s];
        const int seg = sf->segment;
        sum->frames++;
        if (f->fresh_mask & (1u << s)) sum->fresh++;
        if (sf->flags & MOCAP_SENSOR_HELD) sum->held++;
        if (sf->flags & MOCAP_SENSOR_STALE) sum->stale++;
        /* A sensor left out of the calibration, or whose segment the truth lacks, is not scored. */
        if (have && (sf->flags & MOCAP_SENSOR_CALIBRATED) && seg >= 0 && seg < MOCAP_MAX_SENSORS &&
            ((st->truth.segment_mask >> seg) & 1u)) {
            double q[4] = {sf->bone_orientation[0], sf->bone_orientation[1],
                           sf->bone_orientation[2], sf->bone_orientation[3]};
            double angle = quat_angle_deg(q, truth.q[seg]);
            sum->angle_sum += angle;
            sum->angle_sq += angle * angle;
            if (angle > sum->angle_max) sum->angle_max = angle;
            int bin = (int)(angle * 10.0);
            if (bin >= HISTOGRAM_BINS) bin = HISTOGRAM_BINS - 1;
            sum->histogram[bin]++;
            double e2 = 0;
            for (int k = 0; k < 3; ++k) {
                double d = sf->bone_acceleration[k] - truth.a[seg][k];
                e2 += d * d;
            }
            sum->acc_err_sq += e2;
            sum->compared++;
        }
    }
    if (st->csv) {
        fprintf(st->csv, "%llu,%.6f,%u", (unsigned long long)f->sequence, f->time_s, f->flags);
        for (uint32_t s = 0; s < sensors; ++s) {
            const mocap_sensor_frame *sf = &f->sensors[s];
            fprintf(st->csv, ",%.6f,%.6f,%.6f,%.6f,%.4f,%.4f,%.4f,%u", sf->bone_orientation[0],
                    sf->bone_orientation[1], sf->bone_orientation[2], sf->bone_orientation[3],
                    sf->bone_acceleration[0], sf->bone_acceleration[1], sf->bone_acceleration[2],
                    sf->flags);
        }
        fputc('\n', st->csv);
    }
}

/* Drains available frames; returns 1 at the end of the stream. */
static int pump(replay_state *st)
{
    uint32_t n = 0;
    mocap_status s = mocap_session_drain(st->session, st->buffer, DRAIN_CAPACITY, &n);
    for (uint32_t i = 0; i < n; ++i) account_frame(st, &st->buffer[i]);
    if (s == MOCAP_ERR_END_OF_STREAM) return 1;
    if (s == MOCAP_ERR_NO_DATA) mocap_sleep_ms(1);
    return 0;
}

/* Drains frames until the given step has a result, then prints it. 0 when accepted. */
static int wait_for_step(replay_state *st, int step, const char *label, int *ended)
{
    mocap_calibration_report rep;
    for (;;) {
        mocap_calibration_get_step_report(st->session, step, &rep);
        if (rep.state == MOCAP_CALIBRATION_ACCEPTED || rep.state == MOCAP_CALIBRATION_REFUSED) break;
        if (*ended) {
            printf("  %s: the capture ended before the calibration window closed\n", label);
            return 1;
        }
        if (mocapctl_interrupted) return 1;
        *ended = pump(st);
    }
    printf("  %s: %s\n", label, rep.state == MOCAP_CALIBRATION_ACCEPTED ? "accepted" : "REFUSED");
    calibration_print_quality(&rep);
    if (rep.state != MOCAP_CALIBRATION_ACCEPTED) {
        printf("    reason: %s\n", rep.reason);
        return 1;
    }
    return 0;
}

static void print_summary(const replay_state *st, const mocap_session_config *cfg)
{
    mocap_session_stats stats;
    mocap_session_get_stats(st->session, &stats);
    printf("  %llu bytes, %llu HiPNUC frames, %llu CRC failures, %llu bytes skipped, "
           "%llu samples (%llu rejected)\n",
           (unsigned long long)stats.bytes_received, (unsigned long long)stats.frames_decoded,
           (unsigned long long)stats.crc_failures, (unsigned long long)stats.bytes_skipped,
           (unsigned long long)stats.samples_decoded, (unsigned long long)stats.samples_rejected);
    printf("  %llu output frames at %.0f Hz over %.2f s, %llu calibrated\n",
           (unsigned long long)st->frames, cfg->output_rate_hz, st->last_t - st->first_t,
           (unsigned long long)st->calibrated_frames);
    printf("  %-12s %5s %8s %8s %8s", "sensor", "node", "fresh%", "held", "stale");
    if (st->have_truth) printf(" %10s %10s %10s %12s", "mean deg", "p95 deg", "max deg", "acc rms m/s2");
    printf("\n");
    double worst_mean = 0;
    for (uint32_t i = 0; i < cfg->sensor_count && i < MOCAP_MAX_SENSORS; ++i) {
        const sensor_summary *sum = &st->sensors[i];
        printf("  %-12s %5d %7.1f%% %8llu %8llu", mocap_segment_name(cfg->sensor_segments[i]),
               (int)cfg->node_ids[i],
               sum->frames ? 100.0 * (double)sum->fresh / (double)sum->frames : 0.0,
               (unsigned long long)sum->held, (unsigned long long)sum->stale);
        if (st->have_truth && sum->compared) {
            double mean = sum->angle_sum / (double)sum->compared;
            if (mean > worst_mean) worst_mean = mean;
            printf(" %10.3f %10.3f %10.3f %12.3f", mean,
                   histogram_percentile(sum->histogram, sum->compared, 0.95), sum->angle_max,
                   sqrt(sum->acc_err_sq / (double)sum->compared));
        }
        printf("\n");
    }
    if (st->have_truth)
        printf("  bone orientation error against the generator's truth (motion phase): worst sensor "
               "mean %.3f deg\n", worst_mean);
}

int cmd_replay(int argc, char **argv)
{
    if (argc < 1 || argv[0][0] == '-') return mocapctl_usage_error("replay");
    const char *capture = argv[0];
    /* Before any output is opened (they are opened for writing before the capture is read). */
    static const char *const replay_outputs[] = {"--csv", "--json", "--out", "--pose-csv",
                                                 "--metrics-json", "--save-calibration", NULL};
    const char *truth_path = cli_value(argc, argv, "--truth");
    cli_refuse_overwriting(capture, "capture", argc, argv, replay_outputs);
    cli_refuse_overwriting(truth_path, "truth file", argc, argv, replay_outputs);
    const char *cal_path = cli_value(argc, argv, "--calibration");
    const char *save_cal = cli_value(argc, argv, "--save-calibration");
    const char *prelude = cli_value(argc, argv, "--prelude");
    const char *csv_path = cli_value(argc, argv, "--csv");
    const char *rate = cli_value(argc, argv, "--rate");
    /* With the pose model: asked for explicitly, by a pose output, or by a pose truth. */
    if (cli_value(argc, argv, "--model") || cli_value(argc, argv, "--out") ||
        cli_value(argc, argv, "--json") || cli_value(argc, argv, "--pose-csv") ||
        (truth_path && csv_first_row_columns(truth_path) == POSE_TRUTH_COLUMNS))
        return cmd_replay_pose(argc, argv);
    cli_refuse_options(argc, argv, "--smoothing --bvh-order",
                       "applies to the pose model only (--model, --out, --json or --pose-csv)");

    replay_state *st = (replay_state *)calloc(1, sizeof *st);
    if (!st) return 1;
    int rc = 1;
    if (truth_path) {
        if (sensor_truth_load(truth_path, &st->truth) != 0) goto done;
        st->have_truth = 1;
    }
    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    if (sensor_set_from_args(argc, argv, &cfg) != 0) {
        rc = 2;
        goto done;
    }
    if (csv_path) {
        st->csv = mocap_fopen(csv_path, "w");
        if (!st->csv) {
            fprintf(stderr, "mocapctl: cannot write %s\n", csv_path);
            goto done;
        }
        fprintf(st->csv, "sequence,time_s,flags");
        for (uint32_t s = 0; s < cfg.sensor_count; ++s) {
            const char *n = mocap_segment_name(cfg.sensor_segments[s]);
            fprintf(st->csv, ",%s_qw,%s_qx,%s_qy,%s_qz,%s_ax,%s_ay,%s_az,%s_flags", n, n, n, n, n, n, n, n);
        }
        fputc('\n', st->csv);
    }

    cfg.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(cfg.path, sizeof cfg.path, "%s", capture);
    cfg.replay_realtime = cli_flag(argc, argv, "--realtime");
    if (rate) cfg.output_rate_hz = (float)cli_number(argc, argv, "--rate", 60.0, 1.0, 1000.0);

    mocap_status s;
    if (replay_session_open(capture, &cfg, prelude, cal_path, &st->session) != 0) goto done;
    s = mocap_session_start(st->session);
    if (s != MOCAP_OK) {
        rc = report_failure(s, "starting replay");
        goto done;
    }
    printf("replay %s\n", capture);
    int ended = 0;
    if (!cal_path) {
        int heading_rc = wait_for_step(st, MOCAP_CALIBRATION_HEADING, "heading step", &ended);
        int tpose_rc = wait_for_step(st, MOCAP_CALIBRATION_TPOSE, "T-pose step", &ended);
        if (heading_rc != 0 || tpose_rc != 0) goto done;
    }
    while (!ended && !mocapctl_interrupted) ended = pump(st);

    if (save_cal && calibration_save_reported(st->session, save_cal) != 0) goto done; /* rc is still 1 */
    print_summary(st, &cfg);
    rc = report_replay_ended_early(st->session);
    report_capture_damage(st->session, capture);
    report_dropped(st->session, NULL, 0, "the replay",
                   "a replay without --realtime waits instead of dropping");
    if (output_close(&st->csv, csv_path)) rc = 1;
done:
    if (st->session) mocap_session_close(st->session);
    if (st->csv) fclose(st->csv);
    sensor_truth_free(&st->truth);
    free(st);
    return rc;
}
