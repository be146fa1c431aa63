/* mocapctl: the engine without Unity.
 *   mocapctl synth   --out CAPTURE [--truth CSV] [--motion mixed] [--seconds 20] [--world nwu|enu]
 *                    [--noise none|realistic] [--seed N] [--corrupt P] [--dropout P]
 *                    [--trajectory FILE]   (motion from a file, see docs/synth-trajectory.md)
 *   mocapctl replay  CAPTURE [--truth CSV] [--calibration FILE | --prelude H,S,T]
 *                    [--save-calibration FILE] [--csv FRAMES.csv] [--realtime] [--rate HZ]
 *   mocapctl live    --port DEV [--baud 460800] [--record CAPTURE] [--seconds N]
 *   mocapctl record  --port DEV --out CAPTURE [--baud 460800] [--seconds N]
 *   mocapctl bench   decode [--seconds S]
 *   mocapctl infer   --model M.onnx --input IN --output OUT [--stream | --frames T] (tools/infer.c)
 *   mocapctl model-info M.onnx
 *   mocapctl version
 */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "capture_file.h"
#include "mocap_imu.h"
#include "mocap_math.h"
#include "platform.h"
#include "synth.h"

#define DRAIN_CAPACITY 256

int mocapctl_onnx(const char *cmd, int argc, char **argv); /* tools/infer.c */

static volatile sig_atomic_t interrupted = 0;
static void on_interrupt(int sig) { (void)sig; interrupted = 1; }

static int usage(void)
{
    fprintf(stderr,
            "usage:\n"
            "  mocapctl synth --out CAPTURE [--truth CSV] [--motion walk|arms|squat|turn|mixed]\n"
            "                 [--seconds S] [--world nwu|enu] [--noise none|realistic] [--seed N]\n"
            "                 [--corrupt P] [--dropout P] [--trajectory FILE]\n"
            "  mocapctl replay CAPTURE [--truth CSV] [--calibration FILE | --prelude H,S,T]\n"
            "                 [--save-calibration FILE] [--csv FRAMES.csv] [--realtime] [--rate HZ]\n"
            "  mocapctl live --port DEV [--baud B] [--record CAPTURE] [--seconds S]\n"
            "  mocapctl record --port DEV --out CAPTURE [--baud B] [--seconds S]\n"
            "  mocapctl bench decode [--seconds S]\n"
            "  mocapctl infer --model M.onnx --input IN --output OUT [--frames T | --stream] [--batch B]\n"
            "                 [--threads N] [--opt 0-3] [--provider cpu|cuda] [--repeat R]\n"
            "  mocapctl model-info M.onnx\n"
            "  mocapctl version\n");
    return 2;
}

static const char *arg_value(int argc, char **argv, const char *name)
{
    for (int i = 0; i + 1 < argc; ++i)
        if (strcmp(argv[i], name) == 0) return argv[i + 1];
    return NULL;
}

static int arg_flag(int argc, char **argv, const char *name)
{
    for (int i = 0; i < argc; ++i)
        if (strcmp(argv[i], name) == 0) return 1;
    return 0;
}

static int fail(mocap_status st, const char *what)
{
    fprintf(stderr, "mocapctl: %s: %s (%s)\n", what, mocap_last_error(), mocap_status_name(st));
    return 1;
}

/* ---------------------------------------------------------------------------------------- */
/* synth                                                                                       */

static int cmd_synth(int argc, char **argv)
{
    const char *out = arg_value(argc, argv, "--out");
    if (!out) return usage();
    const char *truth = arg_value(argc, argv, "--truth");
    const char *motion_name = arg_value(argc, argv, "--motion");
    const char *world = arg_value(argc, argv, "--world");
    const char *noise = arg_value(argc, argv, "--noise");
    const char *seconds = arg_value(argc, argv, "--seconds");
    const char *seed = arg_value(argc, argv, "--seed");
    const char *corrupt = arg_value(argc, argv, "--corrupt");
    const char *dropout = arg_value(argc, argv, "--dropout");

    synth_config cfg;
    synth_config_defaults(&cfg);
    if (seed) cfg.seed = strtoull(seed, NULL, 10);
    if (seconds) cfg.motion_s = atof(seconds);
    if (world && strcmp(world, "enu") == 0) cfg.world_frame = MOCAP_WORLD_ENU;
    else if (world && strcmp(world, "nwu") != 0) {
        fprintf(stderr, "mocapctl: --world must be nwu or enu\n");
        return 2;
    }
    if (!noise || strcmp(noise, "realistic") == 0) {
        /* Typical of a MEMS IMU at 100 Hz after the device's own fusion. */
        cfg.acc_noise_g = 0.01;
        cfg.gyr_noise_dps = 0.3;
        cfg.quat_noise_deg = 0.3;
        cfg.acc_bias_g = 0.01;
        cfg.still_tremor_deg = 0.2;
    } else if (strcmp(noise, "none") != 0) {
        fprintf(stderr, "mocapctl: --noise must be none or realistic\n");
        return 2;
    }
    if (corrupt) cfg.corrupt_byte_prob = atof(corrupt);
    if (dropout) cfg.node_dropout_prob = atof(dropout);

    synth_trajectory *traj = NULL;
    synth_motion_fn motion = NULL;
    void *motion_user = NULL;
    const char *traj_path = arg_value(argc, argv, "--trajectory");
    if (traj_path) {
        mocap_status st = synth_trajectory_load(traj_path, &traj);
        if (st != MOCAP_OK) return fail(st, "loading trajectory");
        motion = synth_trajectory_motion;
        motion_user = traj;
        if (!seconds) cfg.motion_s = synth_trajectory_duration(traj);
    } else {
        motion = synth_builtin_motion(motion_name ? motion_name : "mixed");
        if (!motion) {
            fprintf(stderr, "mocapctl: unknown motion '%s'\n", motion_name);
            return 2;
        }
    }
    mocap_status st = synth_write_capture(&cfg, motion, motion_user, out, truth);
    synth_trajectory_free(traj);
    if (st != MOCAP_OK) return fail(st, "writing capture");
    printf("wrote %s: %.1f s prelude (heading %.1f s, strap %.1f s, T-pose %.1f s) then the motion, "
           "%s world, seed %llu%s%s\n",
           out, cfg.heading_s + cfg.strap_s + cfg.tpose_s, cfg.heading_s, cfg.strap_s, cfg.tpose_s,
           cfg.world_frame == MOCAP_WORLD_ENU ? "ENU" : "NWU",
           (unsigned long long)cfg.seed, truth ? ", truth " : "", truth ? truth : "");
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* Truth CSV (written by synth_write_capture): t phase (qw qx qy qz ax ay az) x 6               */

typedef struct truth_row {
    double t;
    int phase;
    double q[MOCAP_SENSOR_COUNT][4];
    double a[MOCAP_SENSOR_COUNT][3];
} truth_row;

typedef struct truth_table {
    truth_row *rows;
    size_t count;
    size_t cursor;
} truth_table;

static int truth_load(const char *path, truth_table *table)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot open truth file %s\n", path);
        return -1;
    }
    size_t cap = 4096;
    table->rows = (truth_row *)malloc(cap * sizeof(truth_row));
    table->count = 0;
    table->cursor = 0;
    char line[4096];
    while (table->rows && fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == '\n' || line[0] == 't') continue;
        if (table->count == cap) {
            cap *= 2;
            truth_row *grown = (truth_row *)realloc(table->rows, cap * sizeof(truth_row));
            if (!grown) break;
            table->rows = grown;
        }
        truth_row *r = &table->rows[table->count];
        /* Columns: t_session, phase, then qw qx qy qz ax ay az per segment; ',' or ' ' apart. */
        double values[2 + MOCAP_SENSOR_COUNT * 7];
        int n = 0;
        char *p = line, *end;
        while (n < (int)(sizeof values / sizeof values[0])) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            values[n] = strtod(p, &end);
            if (end == p) break;
            p = end;
            ++n;
        }
        int ok = n == (int)(sizeof values / sizeof values[0]);
        if (ok) {
            r->t = values[0];
            r->phase = (int)values[1];
            for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
                for (int k = 0; k < 4; ++k) r->q[s][k] = values[2 + s * 7 + k];
                for (int k = 0; k < 3; ++k) r->a[s][k] = values[2 + s * 7 + 4 + k];
            }
        }
        if (ok) table->count++;
    }
    fclose(f);
    if (!table->rows || table->count < 2) {
        fprintf(stderr, "mocapctl: truth file %s has no usable rows\n", path);
        free(table->rows);
        table->rows = NULL;
        return -1;
    }
    return 0;
}

/* Truth at time t (rows are in time order; queries arrive in time order). */
static int truth_at(truth_table *table, double t, truth_row *out)
{
    if (t < table->rows[0].t || t > table->rows[table->count - 1].t) return -1;
    while (table->cursor + 1 < table->count && table->rows[table->cursor + 1].t < t) table->cursor++;
    const truth_row *a = &table->rows[table->cursor];
    const truth_row *b = &table->rows[table->cursor + 1 < table->count ? table->cursor + 1 : table->cursor];
    double u = b->t > a->t ? (t - a->t) / (b->t - a->t) : 0.0;
    if (u < 0) u = 0;
    if (u > 1) u = 1;
    out->t = t;
    out->phase = u < 0.5 ? a->phase : b->phase;
    for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
        quat_slerp(out->q[s], a->q[s], b->q[s], u);
        for (int k = 0; k < 3; ++k) out->a[s][k] = a->a[s][k] + u * (b->a[s][k] - a->a[s][k]);
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* replay                                                                                      */

typedef struct sensor_summary {
    uint64_t frames, fresh, held, stale;
    double angle_sum, angle_max, angle_sq;
    double acc_err_sq;
    uint64_t compared;
    uint32_t histogram[1800]; /* 0.1 deg bins */
} sensor_summary;

static double histogram_percentile(const uint32_t *h, uint64_t n, double p)
{
    uint64_t target = (uint64_t)ceil(p * (double)n), seen = 0;
    for (int i = 0; i < 1800; ++i) {
        seen += h[i];
        if (seen >= target && target > 0) return (i + 1) * 0.1;
    }
    return 180.0;
}

static int first_capture_time(const char *path, double *t0)
{
    capture_reader *r = NULL;
    mocap_status st = capture_reader_open(path, &r);
    if (st != MOCAP_OK) return fail(st, "opening capture");
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

static void print_quality(const mocap_calibration_report *rep)
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

/* Waits (draining frames into the summary) until the scheduled step has finished. */
typedef struct replay_state {
    mocap_session *session;
    truth_table truth;
    int have_truth;
    FILE *csv;
    sensor_summary sensors[MOCAP_SENSOR_COUNT];
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
    truth_row truth;
    int have = st->have_truth && (f->flags & MOCAP_FRAME_CALIBRATED) &&
               truth_at(&st->truth, f->time_s, &truth) == 0 && truth.phase == 3;
    for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
        const mocap_sensor_frame *sf = &f->sensors[s];
        sensor_summary *sum = &st->sensors[s];
        sum->frames++;
        if (f->fresh_mask & (1u << s)) sum->fresh++;
        if (sf->flags & MOCAP_SENSOR_HELD) sum->held++;
        if (sf->flags & MOCAP_SENSOR_STALE) sum->stale++;
        if (have) {
            double q[4] = {sf->bone_orientation[0], sf->bone_orientation[1],
                           sf->bone_orientation[2], sf->bone_orientation[3]};
            double angle = quat_angle_deg(q, truth.q[s]);
            sum->angle_sum += angle;
            sum->angle_sq += angle * angle;
            if (angle > sum->angle_max) sum->angle_max = angle;
            int bin = (int)(angle * 10.0);
            if (bin >= 1800) bin = 1799;
            sum->histogram[bin]++;
            double e2 = 0;
            for (int k = 0; k < 3; ++k) {
                double d = sf->bone_acceleration[k] - truth.a[s][k];
                e2 += d * d;
            }
            sum->acc_err_sq += e2;
            sum->compared++;
        }
    }
    if (st->csv) {
        fprintf(st->csv, "%llu,%.6f,%u", (unsigned long long)f->sequence, f->time_s, f->flags);
        for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
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

/* Drains frames until the given step has a result, then prints it. */
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
        if (interrupted) return 1;
        *ended = pump(st);
    }
    printf("  %s: %s\n", label, rep.state == MOCAP_CALIBRATION_ACCEPTED ? "accepted" : "REFUSED");
    print_quality(&rep);
    if (rep.state != MOCAP_CALIBRATION_ACCEPTED) {
        printf("    reason: %s\n", rep.reason);
        return 1;
    }
    return 0;
}

static int cmd_replay(int argc, char **argv)
{
    if (argc < 1 || argv[0][0] == '-') return usage();
    const char *capture = argv[0];
    const char *truth_path = arg_value(argc, argv, "--truth");
    const char *cal_path = arg_value(argc, argv, "--calibration");
    const char *save_cal = arg_value(argc, argv, "--save-calibration");
    const char *prelude = arg_value(argc, argv, "--prelude");
    const char *csv_path = arg_value(argc, argv, "--csv");
    const char *rate = arg_value(argc, argv, "--rate");

    replay_state *st = (replay_state *)calloc(1, sizeof *st);
    if (!st) return 1;
    int rc = 1;
    if (truth_path) {
        if (truth_load(truth_path, &st->truth) != 0) goto done;
        st->have_truth = 1;
    }
    if (csv_path) {
        st->csv = fopen(csv_path, "w");
        if (!st->csv) {
            fprintf(stderr, "mocapctl: cannot write %s\n", csv_path);
            goto done;
        }
        fprintf(st->csv, "sequence,time_s,flags");
        for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
            const char *n = mocap_segment_name(s);
            fprintf(st->csv, ",%s_qw,%s_qx,%s_qy,%s_qz,%s_ax,%s_ay,%s_az,%s_flags", n, n, n, n, n, n, n, n);
        }
        fputc('\n', st->csv);
    }

    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    cfg.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(cfg.path, sizeof cfg.path, "%s", capture);
    cfg.replay_realtime = arg_flag(argc, argv, "--realtime");
    if (rate) cfg.output_rate_hz = (float)atof(rate);

    double t0 = 0;
    if (first_capture_time(capture, &t0) != 0) goto done;
    mocap_status s = mocap_session_open(&cfg, &st->session);
    if (s != MOCAP_OK) {
        rc = fail(s, "opening replay");
        goto done;
    }

    /* Calibration: a saved file, or the windows of the capture's prelude (synth's layout by
     * default: heading 0-3 s, strap 3-5 s, T-pose 5-8 s; the middle of each window is used). */
    double heading_s = 3.0, strap_s = 2.0, tpose_s = 3.0;
    if (prelude && sscanf(prelude, "%lf,%lf,%lf", &heading_s, &strap_s, &tpose_s) != 3) {
        fprintf(stderr, "mocapctl: --prelude wants HEADING,STRAP,TPOSE seconds\n");
        goto done;
    }
    if (cal_path) {
        mocap_calibration cal;
        s = mocap_calibration_load(cal_path, &cal);
        if (s == MOCAP_OK) s = mocap_calibration_set(st->session, &cal);
        if (s != MOCAP_OK) {
            rc = fail(s, "loading calibration");
            goto done;
        }
    } else {
        /* Both windows are queued before the start: a fast replay would outrun us. */
        s = mocap_calibration_schedule(st->session, MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                       (float)(heading_s - 1.0));
        if (s == MOCAP_OK)
            s = mocap_calibration_schedule(st->session, MOCAP_CALIBRATION_TPOSE,
                                           t0 + heading_s + strap_s + 0.5, (float)(tpose_s - 1.0));
        if (s != MOCAP_OK) {
            rc = fail(s, "scheduling calibration");
            goto done;
        }
    }
    s = mocap_session_start(st->session);
    if (s != MOCAP_OK) {
        rc = fail(s, "starting replay");
        goto done;
    }
    printf("replay %s\n", capture);
    int ended = 0;
    if (!cal_path) {
        int heading_rc = wait_for_step(st, MOCAP_CALIBRATION_HEADING, "heading step", &ended);
        int tpose_rc = wait_for_step(st, MOCAP_CALIBRATION_TPOSE, "T-pose step", &ended);
        if (heading_rc != 0 || tpose_rc != 0) goto done;
    }
    while (!ended && !interrupted) ended = pump(st);

    if (save_cal) {
        mocap_calibration cal;
        mocap_calibration_get(st->session, &cal);
        s = mocap_calibration_save(&cal, save_cal);
        if (s != MOCAP_OK) {
            rc = fail(s, "saving calibration");
            goto done;
        }
        printf("  calibration saved to %s\n", save_cal);
    }

    mocap_session_stats stats;
    mocap_session_get_stats(st->session, &stats);
    printf("  %llu bytes, %llu HiPNUC frames, %llu CRC failures, %llu bytes skipped, "
           "%llu samples (%llu rejected)\n",
           (unsigned long long)stats.bytes_received, (unsigned long long)stats.frames_decoded,
           (unsigned long long)stats.crc_failures, (unsigned long long)stats.bytes_skipped,
           (unsigned long long)stats.samples_decoded, (unsigned long long)stats.samples_rejected);
    printf("  %llu output frames at %.0f Hz over %.2f s, %llu calibrated\n",
           (unsigned long long)st->frames, cfg.output_rate_hz, st->last_t - st->first_t,
           (unsigned long long)st->calibrated_frames);
    printf("  %-12s %8s %8s %8s", "sensor", "fresh%", "held", "stale");
    if (st->have_truth) printf(" %10s %10s %10s %12s", "mean deg", "p95 deg", "max deg", "acc rms m/s2");
    printf("\n");
    double worst_mean = 0;
    for (int i = 0; i < MOCAP_SENSOR_COUNT; ++i) {
        sensor_summary *sum = &st->sensors[i];
        printf("  %-12s %7.1f%% %8llu %8llu", mocap_segment_name(i),
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
    rc = 0;
done:
    if (st->session) mocap_session_close(st->session);
    if (st->csv) fclose(st->csv);
    free(st->truth.rows);
    free(st);
    return rc;
}

/* ---------------------------------------------------------------------------------------- */
/* live / record                                                                               */

static int open_live(int argc, char **argv, const char *record_path, mocap_session **out)
{
    const char *port = arg_value(argc, argv, "--port");
    if (!port) return usage();
    const char *baud = arg_value(argc, argv, "--baud");
    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    cfg.source_kind = MOCAP_SOURCE_SERIAL;
    snprintf(cfg.path, sizeof cfg.path, "%s", port);
    if (baud) cfg.baud = (uint32_t)strtoul(baud, NULL, 10);
    if (record_path) snprintf(cfg.capture_path, sizeof cfg.capture_path, "%s", record_path);
    mocap_status s = mocap_session_open(&cfg, out);
    if (s != MOCAP_OK) return fail(s, "opening the receiver");
    s = mocap_session_start(*out);
    if (s != MOCAP_OK) {
        mocap_session_close(*out);
        return fail(s, "starting");
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
    for (int s = 0; s < MOCAP_SENSOR_COUNT; ++s) {
        char c = '.';
        if (f && (f->sensors[s].flags & MOCAP_SENSOR_VALID)) c = (f->fresh_mask & (1u << s)) ? 'o' : 'h';
        if (f && (f->sensors[s].flags & MOCAP_SENSOR_STALE)) c = 'S';
        putchar(c);
    }
    if (cs == MOCAP_CONNECTION_DISCONNECTED) printf("  %s", stats.last_error);
    printf("    ");
    fflush(stdout);
}

/* Refreshes the status line ten times a second until Ctrl-C or limit_s seconds. */
static void show_status_until(mocap_session *session, double limit_s)
{
    int64_t start = mocap_monotonic_ns();
    mocap_frame frame;
    int have = 0;
    while (!interrupted && (double)(mocap_monotonic_ns() - start) * 1e-9 < limit_s) {
        if (mocap_session_poll_latest(session, &frame) == MOCAP_OK) have = 1;
        print_status_line(session, have ? &frame : NULL);
        mocap_sleep_ms(100);
    }
    printf("\n");
}

static int guided_step(mocap_session *session, int step, const char *instruction, float seconds)
{
    printf("\n%s\n", instruction);
    for (int i = 3; i > 0 && !interrupted; --i) {
        printf("  starting in %d...\n", i);
        mocap_sleep_ms(1000);
    }
    mocap_status s = mocap_calibration_schedule(session, step, -1.0, seconds);
    if (s != MOCAP_OK) return fail(s, "scheduling calibration");
    mocap_calibration_report rep;
    mocap_frame frame;
    for (;;) {
        mocap_session_poll_latest(session, &frame);
        mocap_calibration_get_report(session, &rep);
        if (rep.state == MOCAP_CALIBRATION_ACCEPTED || rep.state == MOCAP_CALIBRATION_REFUSED) break;
        printf("\r  hold still: %.1f s  ", rep.seconds_remaining);
        fflush(stdout);
        if (interrupted) return 1;
        mocap_sleep_ms(100);
    }
    printf("\r  %s\n", rep.state == MOCAP_CALIBRATION_ACCEPTED ? "accepted" : "REFUSED");
    print_quality(&rep);
    if (rep.state == MOCAP_CALIBRATION_REFUSED) {
        printf("  reason: %s\n", rep.reason);
        return 1;
    }
    return 0;
}

static int cmd_live(int argc, char **argv)
{
    mocap_session *session = NULL;
    const char *record = arg_value(argc, argv, "--record");
    const char *seconds = arg_value(argc, argv, "--seconds");
    if (open_live(argc, argv, record, &session) != 0) return 1;
    double limit = seconds ? atof(seconds) : 1e30;
    int rc = 0;
    for (int attempt = 0; attempt < 3; ++attempt) {
        rc = guided_step(session, MOCAP_CALIBRATION_HEADING,
                         "Heading step: lay all six sensors still on a flat surface, X axis (the "
                         "arrow) pointing where you will face, Z up.", 3.0f);
        if (rc == 0 || interrupted) break;
    }
    for (int attempt = 0; rc == 0 && attempt < 3; ++attempt) {
        rc = guided_step(session, MOCAP_CALIBRATION_TPOSE,
                         "T-pose step: strap the sensors on (pelvis, wrists, shins, head), face the "
                         "same way, arms straight out to the sides, stand still.", 3.0f);
        if (rc == 0 || interrupted) break;
    }
    if (rc == 0) printf("\nCalibrated. Streaming; Ctrl-C to stop.\n");
    show_status_until(session, limit);
    mocap_session_close(session);
    return rc;
}

static int cmd_record(int argc, char **argv)
{
    const char *out = arg_value(argc, argv, "--out");
    const char *seconds = arg_value(argc, argv, "--seconds");
    if (!out) return usage();
    mocap_session *session = NULL;
    if (open_live(argc, argv, out, &session) != 0) return 1;
    double limit = seconds ? atof(seconds) : 1e30;
    printf("recording to %s; Ctrl-C to stop\n", out);
    show_status_until(session, limit);
    mocap_session_stats stats;
    mocap_session_get_stats(session, &stats);
    mocap_session_close(session);
    printf("recorded %llu bytes from the port (%llu bytes on disk)%s%s\n",
           (unsigned long long)stats.bytes_received,
           (unsigned long long)stats.capture_bytes_written,
           stats.capture_error ? "; recording failed: " : "",
           stats.capture_error ? stats.last_error : "");
    return stats.capture_error ? 1 : 0;
}

/* ---------------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    if (argc < 2) return usage();
    signal(SIGINT, on_interrupt);
    const char *cmd = argv[1];
    if (strcmp(cmd, "synth") == 0) return cmd_synth(argc - 2, argv + 2);
    if (strcmp(cmd, "replay") == 0) return cmd_replay(argc - 2, argv + 2);
    if (strcmp(cmd, "live") == 0) return cmd_live(argc - 2, argv + 2);
    if (strcmp(cmd, "record") == 0) return cmd_record(argc - 2, argv + 2);
    if (strcmp(cmd, "infer") == 0 || strcmp(cmd, "model-info") == 0) return mocapctl_onnx(cmd, argc - 2, argv + 2);
    if (strcmp(cmd, "bench") == 0) {
        if (argc < 3 || strcmp(argv[2], "decode") != 0) return usage();
        const char *seconds = arg_value(argc - 3, argv + 3, "--seconds");
        double mbps = 0;
        return mocapctl_bench_decode(seconds ? atof(seconds) : 3.0, &mbps);
    }
    if (strcmp(cmd, "version") == 0) {
        printf("mocapctl %s (API %d)\n", mocap_version_string(), mocap_api_version());
        return 0;
    }
    return usage();
}
