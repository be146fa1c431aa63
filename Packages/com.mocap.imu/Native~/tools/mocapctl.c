/* mocapctl: the engine without Unity. Its commands and their options are print_usage's text
 * (`mocapctl --help`); the options each accepts are mocapctl_options.h. Beyond that text:
 *   replay runs the pose model (decode -> filter -> calibrate -> model -> drift) when --model,
 *     --out, --json, --pose-csv or a pose truth is given; default model: the shipped fp32 one.
 *   synth --trajectory takes motion from a file (docs/synth-trajectory.md).
 *   stream sends character i's poses to the i-th --vmc.
 *   --smoothing: the solver's one-euro output filter, cut-off at rest (Hz) and its rise per
 *     rad/s of joint speed; default 1,6; 0 = the model's raw output.
 *   bench: tools/bench.c; infer, model-info: tools/infer.c.
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <direct.h>
#include <io.h>
#define WIN32_LEAN_AND_MEAN
#define NOMINMAX
#include <windows.h>
#include <shellapi.h>
#define isatty _isatty
#define getcwd _getcwd
#else
#include <unistd.h>
#endif

#include "bench.h"
#include "cli_args.h"
#include "bvh_writer.h"
#include "capture_file.h"
#include "mocap_imu.h"
#include "mocap_math.h"
#include "mocapctl_options.h"
#include "platform.h"
#include "synth.h"

#define DRAIN_CAPACITY 256
#define POSE_TRUTH_COLS (5 + MOCAP_JOINT_COUNT * 4) /* pose truth CSV columns */

static int csv_first_row_columns(const char *path);
static int cmd_replay_pose(int argc, char **argv);
static int cmd_stream(int argc, char **argv);

int mocapctl_onnx(const char *cmd, int argc, char **argv); /* tools/infer.c */

static volatile sig_atomic_t interrupted = 0;
/* The first Ctrl-C asks the command to finish (flush, close, report); a second one ends the
 * process at once, for a command blocked in I/O that cannot see the first (opening a named pipe
 * nobody writes, writing to a terminal nobody reads). */
static void on_interrupt(int sig)
{
    if (interrupted) {
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    interrupted = 1;
}

/* The usage text: asked for (--help) on stdout with status 0, after a mistake on stderr with 2. */
static int print_usage(FILE *to, int status)
{
    fprintf(to,
            "usage:\n"
            "  mocapctl synth --out CAPTURE [--truth CSV] [--motion walk|arms|squat|turn|mixed]\n"
            "                 [--seconds S] [--world nwu|enu] [--noise none|realistic] [--seed N]\n"
            "                 [--corrupt P] [--dropout P] [--trajectory FILE]\n"
            "  mocapctl replay CAPTURE [--truth CSV] [--calibration FILE | --prelude H,S,T]\n"
            "                 [--save-calibration FILE] [--csv FRAMES.csv] [--realtime] [--rate HZ]\n"
            "  mocapctl replay CAPTURE [--model M.onnx] [--out POSE.bvh] [--bvh-order zxy|xyz]\n"
            "                 [--json POSES.jsonl] [--pose-csv POSES.csv] [--truth CAPTURE.truth.csv]\n"
            "                 [--metrics-json ACCURACY.json]   (with --truth: the accuracy as JSON)\n"
            "                 [--smoothing HZ[,BETA]]   (output filter; default 1,6; 0 = off)\n"
            "  mocapctl live --port DEV [--baud B] [--record CAPTURE] [--seconds S] [--model M | --pose]\n"
            "                 [--smoothing HZ[,BETA]]\n"
            "  mocapctl record --port DEV --out CAPTURE [--baud B] [--seconds S]\n"
            "  mocapctl stream --vmc HOST:PORT [--vmc ...] (--replay CAPTURE [--replay ...] [--realtime]\n"
            "                 [--speed X] [--prelude H,S,T] | --port DEV [--baud B]) [--model M]\n"
            "                 [--rate HZ] [--seconds S] [--allow-remote] [--smoothing HZ[,BETA]]\n"
            "  mocapctl bench decode [--seconds S]\n"
            "  mocapctl bench pipeline|latency|scaling|tip|all [--model M] [--seconds S] [--threads N]\n"
            "                 [--tip-model F] [--max-characters N] [--latency-seconds S]\n"
            "                 [--tip-seconds S]\n"
            "  mocapctl infer --model M.onnx --input IN --output OUT [--frames T | --stream] [--batch B]\n"
            "                 [--threads N] [--opt 0-3] [--provider cpu|cuda] [--repeat R]\n"
            "                 [--ort LIBONNXRUNTIME]\n"
            "  mocapctl model-info M.onnx [--ort LIBONNXRUNTIME]\n"
            "  mocapctl version\n");
    return status;
}

static int usage(void) { return print_usage(stderr, 2); }

/* Options: cli_args.c (a missing value or a bad number is a usage error, exit 2). */
static const char *arg_value(int argc, char **argv, const char *name) { return cli_value(argc, argv, name); }
static int arg_flag(int argc, char **argv, const char *name) { return cli_flag(argc, argv, name); }

static int fail(mocap_status st, const char *what)
{
    fprintf(stderr, "mocapctl: %s: %s (%s)\n", what, mocap_last_error(), mocap_status_name(st));
    return 1;
}

/* The engine's path fields hold MOCAP_PATH_MAX bytes: a longer path would be cut short and
 * open (or, for a recording, overwrite) another file. 0 when it fits. */
static int path_too_long(const char *path, const char *what)
{
    if (strlen(path) < MOCAP_PATH_MAX) return 0;
    fprintf(stderr, "mocapctl: the %s path is %u bytes long; the engine takes at most %d: %s\n",
            what, (unsigned)strlen(path), MOCAP_PATH_MAX - 1, path);
    return 1;
}

/* Closes an output file (CSV, JSON lines) and says whether everything reached it: stdio reports
 * a full disk only through ferror and fclose. 0 when complete; *f becomes NULL either way. */
static int close_output(FILE **f, const char *path)
{
    if (!*f) return 0;
    const int bad = ferror(*f) != 0;
    const int close_failed = fclose(*f) != 0;
    *f = NULL;
    if (!bad && !close_failed) return 0;
    fprintf(stderr, "mocapctl: writing %s failed (%s): the file is incomplete\n", path,
            strerror(errno));
    return 1;
}

/* Inference fails on the solver's thread, where no call returns it: say so at the end of a pose
 * command. 1 when some frame's inference failed (its pose repeats the previous one), else 0. */
static int report_inference_failures(mocap_solver *solver)
{
    mocap_solver_stats st;
    if (!solver || mocap_solver_get_stats(solver, -1, &st) != MOCAP_OK || st.run_failures == 0)
        return 0;
    fprintf(stderr, "mocapctl: inference failed for %llu of %llu frames (%s; their poses repeat "
                    "the previous one)\n  first: %s\n",
            (unsigned long long)st.run_failures, (unsigned long long)st.frames_solved,
            mocap_status_name((mocap_status)st.last_run_status), st.first_run_error);
    if (strcmp(st.first_run_error, st.last_run_error) != 0)
        fprintf(stderr, "  latest: %s\n", st.last_run_error);
    return 1;
}

/* The solver options of the pose commands: --smoothing HZ[,BETA] (one-euro output filter:
 * cut-off at rest, Hz, and its rise per rad/s; 0 = the model's raw output). 0 or 2 (usage). */
static int solver_config_from_args(int argc, char **argv, mocap_solver_config *out)
{
    mocap_solver_config_defaults(out);
    const char *smoothing = arg_value(argc, argv, "--smoothing");
    if (!smoothing) return 0;
    char *end = NULL;
    double hz = strtod(smoothing, &end), beta = out->smoothing_beta;
    int bad = end == smoothing;
    if (!bad && *end == ',') {
        const char *b = end + 1;
        beta = strtod(b, &end);
        bad = end == b;
    }
    if (bad || *end != '\0' || !(hz >= 0.0 && hz < 1e6) || !(beta >= 0.0 && beta < 1e6)) {
        fprintf(stderr, "mocapctl: --smoothing wants HZ or HZ,BETA with HZ >= 0 (0: off) and "
                        "BETA >= 0, got '%s'\n", smoothing);
        return 2;
    }
    out->smoothing_min_cutoff_hz = (float)hz;
    out->smoothing_beta = (float)beta;
    return 0;
}

/* --save-calibration of both replay modes: the session's calibration to path; 0 or 1. */
static int save_calibration(mocap_session *session, const char *path)
{
    mocap_calibration cal;
    mocap_calibration_get(session, &cal);
    mocap_status s = mocap_calibration_save(&cal, path);
    if (s != MOCAP_OK) return fail(s, "saving calibration");
    printf("  calibration saved to %s\n", path);
    return 0;
}

/* ---------------------------------------------------------------------------------------- */
/* synth                                                                                       */

static int cmd_synth(int argc, char **argv)
{
    const char *out = arg_value(argc, argv, "--out");
    if (!out) return usage();
    const char *truth = arg_value(argc, argv, "--truth");
    static const char *const synth_outputs[] = {"--out", "--truth", NULL};
    cli_refuse_overwriting(arg_value(argc, argv, "--trajectory"), "trajectory", argc, argv, synth_outputs);
    const char *motion_name = arg_value(argc, argv, "--motion");
    const char *world = arg_value(argc, argv, "--world");
    const char *noise = arg_value(argc, argv, "--noise");

    synth_config cfg;
    synth_config_defaults(&cfg);
    cfg.seed = cli_u64(argc, argv, "--seed", cfg.seed);
    cfg.motion_s = cli_number(argc, argv, "--seconds", cfg.motion_s, 0.0, 86400.0);
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
    cfg.corrupt_byte_prob = cli_number(argc, argv, "--corrupt", cfg.corrupt_byte_prob, 0.0, 1.0);
    cfg.node_dropout_prob = cli_number(argc, argv, "--dropout", cfg.node_dropout_prob, 0.0, 1.0);

    synth_trajectory *traj = NULL;
    synth_motion_fn motion = NULL;
    void *motion_user = NULL;
    const char *traj_path = arg_value(argc, argv, "--trajectory");
    if (traj_path) {
        mocap_status st = synth_trajectory_load(traj_path, &traj);
        if (st != MOCAP_OK) return fail(st, "loading trajectory");
        motion = synth_trajectory_motion;
        motion_user = traj;
        if (!arg_value(argc, argv, "--seconds")) cfg.motion_s = synth_trajectory_duration(traj);
    } else {
        motion = synth_builtin_motion(motion_name ? motion_name : "mixed");
        if (!motion) {
            fprintf(stderr, "mocapctl: unknown motion '%s'\n", motion_name);
            return 2;
        }
    }
    /* A motion ends where it ends: --seconds can shorten it, not lengthen it. */
    const double motion_length = synth_motion_duration(motion, motion_user, 86400.0);
    const int clipped = arg_value(argc, argv, "--seconds") && cfg.motion_s > motion_length + 1e-3;
    mocap_status st = synth_write_capture(&cfg, motion, motion_user, out, truth);
    synth_trajectory_free(traj);
    if (st != MOCAP_OK) return fail(st, "writing capture");
    printf("wrote %s: %.1f s prelude (heading %.1f s, strap %.1f s, T-pose %.1f s) then %.1f s of "
           "%s, %s world, seed %llu%s%s\n",
           out, cfg.heading_s + cfg.strap_s + cfg.tpose_s, cfg.heading_s, cfg.strap_s, cfg.tpose_s,
           cfg.motion_s < motion_length ? cfg.motion_s : motion_length,
           traj_path ? "the trajectory" : motion_name ? motion_name : "mixed",
           cfg.world_frame == MOCAP_WORLD_ENU ? "ENU" : "NWU",
           (unsigned long long)cfg.seed, truth ? ", truth " : "", truth ? truth : "");
    if (clipped)
        fprintf(stderr, "mocapctl: note: the motion ends after %.1f s, so the capture is shorter "
                        "than --seconds %s\n", motion_length, arg_value(argc, argv, "--seconds"));
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
    FILE *f = mocap_fopen(path, "r");
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
        /* The phase becomes an int: only a small whole number may (a damaged row is skipped). */
        int ok = n == (int)(sizeof values / sizeof values[0]) && values[1] >= -1e6 && values[1] <= 1e6;
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

/* A replay whose file stopped reading ends early, with the cause in the stats: say so and fail
 * (the output covers only part of the capture). Returns 0 when the replay read to the end. */
static int replay_ended_early(mocap_session *session)
{
    mocap_session_stats stats;
    if (mocap_session_get_stats(session, &stats) != MOCAP_OK || stats.last_error[0] == '\0') return 0;
    fprintf(stderr, "mocapctl: the replay stopped before the end of the capture: %s\n", stats.last_error);
    return 1;
}

/* A realtime replay paced faster than processing (a high --speed on a slow machine), or a live
 * session whose consumer stalled, loses data on the way: the engine counts it (input bytes,
 * frames, poses) but says nothing. Say so after the run; `solver` may be NULL. */
static void report_dropped(mocap_session *session, mocap_solver *solver, int32_t character,
                           const char *what, const char *remedy)
{
    mocap_session_stats ss;
    mocap_solver_stats ps;
    unsigned long long bytes = 0, frames = 0, poses = 0;
    if (mocap_session_get_stats(session, &ss) == MOCAP_OK) {
        bytes = (unsigned long long)ss.bytes_dropped;
        frames = (unsigned long long)ss.frames_dropped;
    }
    if (solver && mocap_solver_get_stats(solver, character, &ps) == MOCAP_OK)
        poses = (unsigned long long)ps.poses_dropped;
    if (bytes == 0 && frames == 0 && poses == 0) return;
    fprintf(stderr, "mocapctl: warning: %s: processing fell behind and lost %llu frame(s), %llu "
                    "pose(s) and %llu input byte(s) on the way; %s\n",
            what, frames, poses, bytes, remedy);
}

/* The replay skips damaged chunks and a cut-off end, as it must for a crash-damaged file; say
 * so after the run, so that output made from part of a capture is not taken for the whole. */
static void report_capture_damage(mocap_session *session, const char *capture)
{
    mocap_session_stats stats;
    if (mocap_session_get_stats(session, &stats) != MOCAP_OK) return;
    if (stats.replay_chunks_skipped > 0)
        fprintf(stderr, "mocapctl: warning: capture %s: %llu damaged chunk(s) were skipped; what they "
                        "held is missing from the results\n",
                capture, (unsigned long long)stats.replay_chunks_skipped);
    if (stats.replay_tail_damaged)
        fprintf(stderr, "mocapctl: warning: capture %s ends in a damaged or incomplete chunk (a "
                        "recording cut short?); its last records are missing from the results\n", capture);
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

/* Opens a replay of capture and arranges its calibration: a saved file (cal_path), or the
 * heading and T-pose windows of the capture's prelude (prelude "H,S,T" seconds; synth's layout
 * by default: heading 0-3 s, strap 3-5 s, T-pose 5-8 s; the middle of each window is used), both
 * queued before the start because a fast replay would outrun a caller reacting to results.
 * Returns 0, or 1 after printing why. */
static int open_replay_session(const char *capture, mocap_session_config *cfg, const char *prelude,
                               const char *cal_path, mocap_session **out)
{
    double t0 = 0;
    if (path_too_long(capture, "capture")) return 1;
    if (first_capture_time(capture, &t0) != 0) return 1;
    double heading_s = 3.0, strap_s = 2.0, tpose_s = 3.0;
    if (prelude && sscanf(prelude, "%lf,%lf,%lf", &heading_s, &strap_s, &tpose_s) != 3) {
        fprintf(stderr, "mocapctl: --prelude wants HEADING,STRAP,TPOSE seconds\n");
        return 1;
    }
    mocap_status s = mocap_session_open(cfg, out);
    if (s != MOCAP_OK) return fail(s, "opening replay");
    if (cal_path) {
        mocap_calibration cal;
        s = mocap_calibration_load(cal_path, &cal);
        if (s == MOCAP_OK) s = mocap_calibration_set(*out, &cal);
        if (s != MOCAP_OK) return fail(s, "loading calibration");
        return 0;
    }
    s = mocap_calibration_schedule(*out, MOCAP_CALIBRATION_HEADING, t0 + 0.5,
                                   (float)(heading_s - 1.0));
    if (s == MOCAP_OK)
        s = mocap_calibration_schedule(*out, MOCAP_CALIBRATION_TPOSE,
                                       t0 + heading_s + strap_s + 0.5, (float)(tpose_s - 1.0));
    if (s != MOCAP_OK) return fail(s, "scheduling calibration");
    return 0;
}

static int cmd_replay(int argc, char **argv)
{
    if (argc < 1 || argv[0][0] == '-') return usage();
    const char *capture = argv[0];
    /* Before any output is opened (they are opened for writing before the capture is read). */
    static const char *const replay_outputs[] = {"--csv", "--json", "--out", "--pose-csv",
                                                 "--metrics-json", "--save-calibration", NULL};
    const char *truth_path = arg_value(argc, argv, "--truth");
    cli_refuse_overwriting(capture, "capture", argc, argv, replay_outputs);
    cli_refuse_overwriting(truth_path, "truth file", argc, argv, replay_outputs);
    const char *cal_path = arg_value(argc, argv, "--calibration");
    const char *save_cal = arg_value(argc, argv, "--save-calibration");
    const char *prelude = arg_value(argc, argv, "--prelude");
    const char *csv_path = arg_value(argc, argv, "--csv");
    const char *rate = arg_value(argc, argv, "--rate");
    /* With the pose model: asked for explicitly, by a pose output, or by a pose truth. */
    if (arg_value(argc, argv, "--model") || arg_value(argc, argv, "--out") ||
        arg_value(argc, argv, "--json") || arg_value(argc, argv, "--pose-csv") ||
        (truth_path && csv_first_row_columns(truth_path) == POSE_TRUTH_COLS))
        return cmd_replay_pose(argc, argv);
    cli_refuse_options(argc, argv, "--smoothing --bvh-order",
                       "applies to the pose model only (--model, --out, --json or --pose-csv)");

    replay_state *st = (replay_state *)calloc(1, sizeof *st);
    if (!st) return 1;
    int rc = 1;
    if (truth_path) {
        if (truth_load(truth_path, &st->truth) != 0) goto done;
        st->have_truth = 1;
    }
    if (csv_path) {
        st->csv = mocap_fopen(csv_path, "w");
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
    if (rate) cfg.output_rate_hz = (float)cli_number(argc, argv, "--rate", 60.0, 1.0, 1000.0);

    mocap_status s;
    if (open_replay_session(capture, &cfg, prelude, cal_path, &st->session) != 0) goto done;
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

    if (save_cal && save_calibration(st->session, save_cal) != 0) goto done; /* rc is still 1 */

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
    rc = replay_ended_early(st->session);
    report_capture_damage(st->session, capture);
    report_dropped(st->session, NULL, 0, "the replay",
                   "a replay without --realtime waits instead of dropping");
    if (close_output(&st->csv, csv_path)) rc = 1;
done:
    if (st->session) mocap_session_close(st->session);
    if (st->csv) fclose(st->csv);
    free(st->truth.rows);
    free(st);
    return rc;
}

/* ---------------------------------------------------------------------------------------- */
/* Pose model: model path, pose truth, metrics, pose replay                                   */

#define SHIPPED_MODEL "Packages/com.mocap.imu/Runtime/Models/mocap_pose_fp32.onnx"
#define POSE_DRAIN 256

static int file_exists(const char *path)
{
    FILE *f = mocap_fopen(path, "rb");
    if (!f) return 0;
    fclose(f);
    return 1;
}

/* Looks for SHIPPED_MODEL in dir and its parents (up to 8 levels). */
static int find_upwards(const char *dir, char *out, size_t cap)
{
    char base[2048];
    snprintf(base, sizeof base, "%.2000s", dir);
    for (int level = 0; level < 8 && base[0]; ++level) {
        snprintf(out, cap, "%s/%s", base, SHIPPED_MODEL);
        if (file_exists(out)) return 1;
        char *slash = strrchr(base, '/');
        if (!slash) break;
        if (slash == base) {
            base[1] = 0;
            if (level > 0 && strcmp(base, "/") == 0) break;
        } else {
            *slash = 0;
        }
    }
    return 0;
}

/* The shipped fp32 model: $MOCAP_MODEL, else found above the executable, else above the current
 * directory, else where the build was configured from (MOCAP_SHIPPED_MODEL). Returns 0 and fills out, or -1 with the places it looked in `out`. */
static int default_model_path(char *out, size_t cap)
{
    const char *env = getenv("MOCAP_MODEL");
    if (env && env[0]) {
        snprintf(out, cap, "%s", env);
        return 0;
    }
    char exe[4096] = "";
#if defined(__linux__)
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n > 0) exe[n] = 0;
    else exe[0] = 0;
#endif
    if (exe[0]) {
        char *slash = strrchr(exe, '/');
        if (slash) *slash = 0;
        if (find_upwards(exe, out, cap)) return 0;
    }
    char cwd[4096];
    if (getcwd(cwd, sizeof cwd) && find_upwards(cwd, out, cap)) return 0;
#if defined(MOCAP_SHIPPED_MODEL)
    if (file_exists(MOCAP_SHIPPED_MODEL)) {
        snprintf(out, cap, "%s", MOCAP_SHIPPED_MODEL);
        return 0;
    }
#endif
    snprintf(out, cap, "%s above %s or the current directory (set --model or MOCAP_MODEL)",
             SHIPPED_MODEL, exe[0] ? exe : "the executable");
    return -1;
}

/* Pose truth CSV (training synth-capture): t_session, motion, root xyz, 24 x (qw qx qy qz). */
typedef struct pose_truth_row {
    double t;
    int motion;
    double root[3];
    double q[MOCAP_JOINT_COUNT][4];
} pose_truth_row;

typedef struct pose_truth {
    pose_truth_row *rows;
    size_t count, cursor;
} pose_truth;

/* Columns of the first data line of a CSV (0 when none). */
static int csv_first_row_columns(const char *path)
{
    FILE *f = mocap_fopen(path, "r");
    if (!f) return -1;
    static char line[16384];
    int cols = 0;
    while (fgets(line, sizeof line, f)) {
        if (!((line[0] >= '0' && line[0] <= '9') || line[0] == '-')) continue;
        char *p = line, *end;
        for (;;) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            strtod(p, &end);
            if (end == p) break;
            p = end;
            ++cols;
        }
        break;
    }
    fclose(f);
    return cols;
}

static int pose_truth_load(const char *path, pose_truth *pt)
{
    memset(pt, 0, sizeof *pt);
    FILE *f = mocap_fopen(path, "r");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot open truth file %s\n", path);
        return -1;
    }
    size_t cap = 4096;
    pt->rows = (pose_truth_row *)malloc(cap * sizeof *pt->rows);
    static char line[16384];
    while (pt->rows && fgets(line, sizeof line, f)) {
        if (!((line[0] >= '0' && line[0] <= '9') || line[0] == '-')) continue;
        double v[POSE_TRUTH_COLS];
        int n = 0;
        char *p = line, *end;
        while (n < POSE_TRUTH_COLS) {
            while (*p == ',' || *p == ' ' || *p == '\t') ++p;
            v[n] = strtod(p, &end);
            if (end == p) break;
            p = end;
            ++n;
        }
        if (n != POSE_TRUTH_COLS || !(v[1] >= -1e6 && v[1] <= 1e6)) continue; /* (int) below */
        if (pt->count == cap) {
            cap *= 2;
            pose_truth_row *g = (pose_truth_row *)realloc(pt->rows, cap * sizeof *g);
            if (!g) break;
            pt->rows = g;
        }
        pose_truth_row *r = &pt->rows[pt->count++];
        r->t = v[0];
        r->motion = (int)v[1];
        for (int k = 0; k < 3; ++k) r->root[k] = v[2 + k];
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            for (int k = 0; k < 4; ++k) r->q[j][k] = v[5 + j * 4 + k];
            quat_normalize(r->q[j]);
        }
    }
    fclose(f);
    if (!pt->rows || pt->count < 2) {
        fprintf(stderr, "mocapctl: pose truth %s has no usable rows (expected %d columns: "
                "t_session, motion, root xyz, 24 x qw qx qy qz)\n", path, POSE_TRUTH_COLS);
        free(pt->rows);
        pt->rows = NULL;
        return -1;
    }
    return 0;
}

static int pose_truth_at(pose_truth *pt, double t, pose_truth_row *out)
{
    if (t < pt->rows[0].t - 1e-6 || t > pt->rows[pt->count - 1].t + 1e-6) return -1;
    while (pt->cursor + 1 < pt->count && pt->rows[pt->cursor + 1].t < t) pt->cursor++;
    const pose_truth_row *a = &pt->rows[pt->cursor];
    const pose_truth_row *b = &pt->rows[pt->cursor + 1 < pt->count ? pt->cursor + 1 : pt->cursor];
    double u = b->t > a->t ? (t - a->t) / (b->t - a->t) : 0.0;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    out->t = t;
    out->motion = u < 0.5 ? a->motion : b->motion;
    for (int k = 0; k < 3; ++k) out->root[k] = a->root[k] + u * (b->root[k] - a->root[k]);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) quat_slerp(out->q[j], a->q[j], b->q[j], u);
    return 0;
}

/* Global rotations and root-relative positions of a pose given local quaternions (joint 0
 * global) on the model's skeleton. */
static void fk(const mocap_model_info *info, const double q[MOCAP_JOINT_COUNT][4],
               double g[MOCAP_JOINT_COUNT][4], double p[MOCAP_JOINT_COUNT][3])
{
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        int parent = info->joint_parents[j];
        if (parent < 0) {
            quat_copy(g[j], q[j]);
            p[j][0] = p[j][1] = p[j][2] = 0.0;
            continue;
        }
        quat_multiply(g[j], g[parent], q[j]);
        double off[3] = {info->rest_offsets[j][0], info->rest_offsets[j][1], info->rest_offsets[j][2]};
        double r[3];
        quat_rotate(r, g[parent], off);
        for (int k = 0; k < 3; ++k) p[j][k] = p[parent][k] + r[k];
    }
}

/* The DIP/TransPose 15-joint subset (no pelvis, ankles, feet, wrists, hands) and SIP joints. */
static int dip_joint(int j)
{
    return !(j == 0 || j == 7 || j == 8 || j == 10 || j == 11 || j == 20 || j == 21 || j == 22 || j == 23);
}
static const int SIP_JOINTS[4] = {1, 2, 16, 17};

typedef struct pose_metrics {
    uint64_t compared;
    double angle_all, angle_dip, sip, pos_cm;
    double jitter_sum, truth_jitter_sum;
    uint64_t jitter_n;
    double hist_p[3][MOCAP_JOINT_COUNT][3], hist_t[3][MOCAP_JOINT_COUNT][3];
    int hist_len;
    uint64_t last_frame_sequence;
    /* per compared pose, for drift windows */
    double *pred_root, *vel_root, *true_root, *times;
    size_t cap;
} pose_metrics;

static void metrics_add(pose_metrics *m, const mocap_model_info *info, const mocap_pose *pose,
                        const pose_truth_row *truth, double fps)
{
    double qp[MOCAP_JOINT_COUNT][4], gp[MOCAP_JOINT_COUNT][4], gt[MOCAP_JOINT_COUNT][4];
    double pp[MOCAP_JOINT_COUNT][3], ptr[MOCAP_JOINT_COUNT][3];
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        for (int k = 0; k < 4; ++k) qp[j][k] = pose->joint_rotations[j][k];
        if (quat_normalize(qp[j]) != 0) quat_identity(qp[j]);
    }
    fk(info, (const double(*)[4])qp, gp, pp);
    fk(info, truth->q, gt, ptr);
    double all = 0, dip = 0, sip = 0, pos = 0;
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        double a = quat_angle_deg(qp[j], truth->q[j]);
        all += a;
        if (dip_joint(j)) dip += a;
        double d2 = 0;
        for (int k = 0; k < 3; ++k) d2 += (pp[j][k] - ptr[j][k]) * (pp[j][k] - ptr[j][k]);
        pos += sqrt(d2);
    }
    for (int i = 0; i < 4; ++i) sip += quat_angle_deg(gp[SIP_JOINTS[i]], gt[SIP_JOINTS[i]]);
    m->angle_all += all / MOCAP_JOINT_COUNT;
    m->angle_dip += dip / 15.0;
    m->sip += sip / 4.0;
    m->pos_cm += 100.0 * pos / MOCAP_JOINT_COUNT;

    /* Jitter: third difference of root-aligned positions over consecutive frames. */
    if (m->compared > 0 && pose->frame_sequence != m->last_frame_sequence + 1) m->hist_len = 0;
    m->last_frame_sequence = pose->frame_sequence;
    if (m->hist_len == 3) {
        double jp = 0, jt = 0;
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double a2 = 0, b2 = 0;
            for (int k = 0; k < 3; ++k) {
                double dp = pp[j][k] - 3 * m->hist_p[2][j][k] + 3 * m->hist_p[1][j][k] - m->hist_p[0][j][k];
                double dt = ptr[j][k] - 3 * m->hist_t[2][j][k] + 3 * m->hist_t[1][j][k] - m->hist_t[0][j][k];
                a2 += dp * dp;
                b2 += dt * dt;
            }
            jp += sqrt(a2);
            jt += sqrt(b2);
        }
        const double f3 = fps * fps * fps;
        m->jitter_sum += jp / MOCAP_JOINT_COUNT * f3;
        m->truth_jitter_sum += jt / MOCAP_JOINT_COUNT * f3;
        m->jitter_n++;
        memmove(m->hist_p[0], m->hist_p[1], 2 * sizeof m->hist_p[0]);
        memmove(m->hist_t[0], m->hist_t[1], 2 * sizeof m->hist_t[0]);
        m->hist_len = 2;
    }
    memcpy(m->hist_p[m->hist_len], pp, sizeof pp);
    memcpy(m->hist_t[m->hist_len], ptr, sizeof ptr);
    m->hist_len++;

    if (m->compared == m->cap) {
        size_t cap = m->cap ? m->cap * 2 : 4096;
        double *a = (double *)realloc(m->pred_root, cap * 3 * sizeof(double));
        if (a) m->pred_root = a;
        double *v = (double *)realloc(m->vel_root, cap * 3 * sizeof(double));
        if (v) m->vel_root = v;
        double *b = (double *)realloc(m->true_root, cap * 3 * sizeof(double));
        if (b) m->true_root = b;
        double *t = (double *)realloc(m->times, cap * sizeof(double));
        if (t) m->times = t;
        if (!a || !b || !t || !v) return;
        m->cap = cap;
    }
    size_t i = m->compared;
    for (int k = 0; k < 3; ++k) {
        m->pred_root[i * 3 + k] = pose->root_position[k];
        /* Integrated model velocity (no drift correction), as training/evaluate.py measures. */
        m->vel_root[i * 3 + k] = (i ? m->vel_root[(i - 1) * 3 + k] : 0.0) +
                                 (i ? pose->root_velocity[k] / fps : 0.0);
        m->true_root[i * 3 + k] = truth->root[k];
    }
    m->times[i] = pose->time_s;
    m->compared++;
}

/* Mean root drift over windows of w seconds starting every second: |d_pred - d_true| (m). */
static double drift_mean(const pose_metrics *m, const double *pred, double window_s, int *count)
{
    double sum = 0;
    int n = 0;
    size_t j = 0;
    double next_start = m->compared ? m->times[0] : 0;
    for (size_t i = 0; i < m->compared; ++i) {
        if (m->times[i] + 1e-9 < next_start) continue;
        next_start = m->times[i] + 1.0;
        if (j < i) j = i;
        while (j < m->compared && m->times[j] < m->times[i] + window_s - 1e-6) ++j;
        if (j >= m->compared) break;
        double e2 = 0;
        for (int k = 0; k < 3; ++k) {
            double dp = pred[j * 3 + k] - pred[i * 3 + k];
            double dt = m->true_root[j * 3 + k] - m->true_root[i * 3 + k];
            e2 += (dp - dt) * (dp - dt);
        }
        sum += sqrt(e2);
        ++n;
    }
    *count = n;
    return n ? sum / n : NAN;
}

static void metrics_print(const pose_metrics *m, const char *truth_path)
{
    if (!m->compared) {
        printf("  pose accuracy: no pose fell inside the truth's time range (%s)\n", truth_path);
        return;
    }
    const double n = (double)m->compared;
    printf("  pose accuracy against %s (%llu poses, %.1f s; the whole byte-level pipeline):\n",
           truth_path, (unsigned long long)m->compared, m->times[m->compared - 1] - m->times[0]);
    printf("    joint angle error: %.2f deg (24 joints), %.2f deg (15 DIP joints), SIP %.2f deg\n",
           m->angle_all / n, m->angle_dip / n, m->sip / n);
    printf("    joint position error (root-aligned): %.2f cm\n", m->pos_cm / n);
    static const double windows[3] = {2.0, 5.0, 10.0};
    printf("    root drift (pose root, drift-corrected):");
    for (int w = 0; w < 3; ++w) {
        int c = 0;
        double d = drift_mean(m, m->pred_root, windows[w], &c);
        printf(" %gs %.3f m%s", windows[w], d, w < 2 ? "," : "");
        (void)c;
    }
    printf("\n    root drift (integrated root_velocity):");
    for (int w = 0; w < 3; ++w) {
        int c = 0;
        double d = drift_mean(m, m->vel_root, windows[w], &c);
        printf(" %gs %.3f m%s", windows[w], d, w < 2 ? "," : "");
    }
    printf("\n    jitter: %.2f x10^2 m/s^3 (truth %.2f)\n",
           m->jitter_n ? m->jitter_sum / (double)m->jitter_n / 100.0 : NAN,
           m->jitter_n ? m->truth_jitter_sum / (double)m->jitter_n / 100.0 : NAN);
}

/* A number for JSON: NaN and infinities (no pose, no drift window) become null. */
static void json_number(FILE *f, const char *key, double value, const char *after)
{
    if (isfinite(value)) fprintf(f, "\"%s\":%.6g%s", key, value, after);
    else fprintf(f, "\"%s\":null%s", key, after);
}

/* The figures metrics_print shows, for scripts and tests (--metrics-json). 0 when written. */
static int metrics_write_json(const pose_metrics *m, const char *truth_path, const char *path)
{
    FILE *f = mocap_fopen(path, "w");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot write %s\n", path);
        return 1;
    }
    const double n = m->compared ? (double)m->compared : NAN;
    fputs("{", f);
    fputs("\"truth\":\"", f);
    for (const char *c = truth_path; *c; ++c) {
        if (*c == '"' || *c == '\\') fputc('\\', f);
        if ((unsigned char)*c >= 0x20) fputc(*c, f);
    }
    fprintf(f, "\",\"poses\":%llu,", (unsigned long long)m->compared);
    json_number(f, "seconds", m->compared ? m->times[m->compared - 1] - m->times[0] : NAN, ",");
    json_number(f, "angle_error_deg", m->angle_all / n, ",");
    json_number(f, "angle_error_dip_deg", m->angle_dip / n, ",");
    json_number(f, "sip_error_deg", m->sip / n, ",");
    json_number(f, "position_error_cm", m->pos_cm / n, ",");
    static const double windows[3] = {2.0, 5.0, 10.0};
    static const char *const drift_keys[3] = {"2s", "5s", "10s"};
    const double *roots[2] = {m->pred_root, m->vel_root};
    static const char *const root_keys[2] = {"root_drift_m", "root_drift_integrated_velocity_m"};
    for (int r = 0; r < 2; ++r) {
        fprintf(f, "\"%s\":{", root_keys[r]);
        for (int w = 0; w < 3; ++w) {
            int count = 0;
            double d = m->compared ? drift_mean(m, roots[r], windows[w], &count) : NAN;
            json_number(f, drift_keys[w], d, w < 2 ? "," : "},");
        }
    }
    json_number(f, "jitter_100m_s3", m->jitter_n ? m->jitter_sum / (double)m->jitter_n / 100.0 : NAN, ",");
    json_number(f, "truth_jitter_100m_s3",
                m->jitter_n ? m->truth_jitter_sum / (double)m->jitter_n / 100.0 : NAN, "}\n");
    return close_output(&f, path);
}

static void write_pose_json(FILE *f, const mocap_pose *p)
{
    fprintf(f, "{\"sequence\":%llu,\"frame_sequence\":%llu,\"time_s\":%.6f,\"flags\":%u,"
               "\"root_position\":[%.6f,%.6f,%.6f],\"root_velocity\":[%.6f,%.6f,%.6f],"
               "\"foot_contact\":[%.4f,%.4f],\"joint_rotations\":[",
            (unsigned long long)p->sequence, (unsigned long long)p->frame_sequence, p->time_s,
            p->flags, p->root_position[0], p->root_position[1], p->root_position[2],
            p->root_velocity[0], p->root_velocity[1], p->root_velocity[2], p->foot_contact[0],
            p->foot_contact[1]);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        fprintf(f, "%s[%.6f,%.6f,%.6f,%.6f]", j ? "," : "", p->joint_rotations[j][0],
                p->joint_rotations[j][1], p->joint_rotations[j][2], p->joint_rotations[j][3]);
    fputs("],\"joint_positions\":[", f);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        fprintf(f, "%s[%.6f,%.6f,%.6f]", j ? "," : "", p->joint_positions[j][0],
                p->joint_positions[j][1], p->joint_positions[j][2]);
    fputs("]}\n", f);
}

static void write_pose_csv_header(FILE *f, const mocap_model_info *info)
{
    fputs("sequence,frame_sequence,time_s,flags,root_x,root_y,root_z,vel_x,vel_y,vel_z,"
          "contact_left,contact_right", f);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        const char *n = info->joint_names[j];
        fprintf(f, ",%s_qw,%s_qx,%s_qy,%s_qz", n, n, n, n);
    }
    fputc('\n', f);
}

static void write_pose_csv(FILE *f, const mocap_pose *p)
{
    fprintf(f, "%llu,%llu,%.6f,%u,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f",
            (unsigned long long)p->sequence, (unsigned long long)p->frame_sequence, p->time_s,
            p->flags, p->root_position[0], p->root_position[1], p->root_position[2],
            p->root_velocity[0], p->root_velocity[1], p->root_velocity[2], p->foot_contact[0],
            p->foot_contact[1]);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        fprintf(f, ",%.6f,%.6f,%.6f,%.6f", p->joint_rotations[j][0], p->joint_rotations[j][1],
                p->joint_rotations[j][2], p->joint_rotations[j][3]);
    fputc('\n', f);
}

/* Opens the model (explicit path or the shipped one) and prints what it is. */
static int open_model(const char *model_arg, mocap_model **model, mocap_model_info *info)
{
    char path[4096];
    if (model_arg) {
        snprintf(path, sizeof path, "%s", model_arg);
    } else if (default_model_path(path, sizeof path) != 0) {
        fprintf(stderr, "mocapctl: no --model given and the shipped model was not found: %s\n", path);
        return 1;
    }
    mocap_status s = mocap_model_open(path, NULL, model);
    if (s != MOCAP_OK) {
        fprintf(stderr, "mocapctl: loading model %s: %s (%s)\n", path, mocap_last_error(),
                mocap_status_name(s));
        return 1;
    }
    mocap_model_get_info(*model, info);
    printf("model %s: %s, %s, %.0f Hz, state %d x %d\n", path, info->model_name, info->precision,
           info->frame_rate, info->state_layers, info->state_size);
    return 0;
}

static long file_size(const char *path)
{
    FILE *f = mocap_fopen(path, "rb");
    if (!f) return -1;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fclose(f);
    return n;
}

/* Prints a calibration step's result once it has one; returns 1 when it has. */
static int report_step_once(mocap_session *session, int step, const char *label, int *done, int *failed)
{
    if (*done) return 1;
    mocap_calibration_report rep;
    if (mocap_calibration_get_step_report(session, step, &rep) != MOCAP_OK) return 0;
    if (rep.state != MOCAP_CALIBRATION_ACCEPTED && rep.state != MOCAP_CALIBRATION_REFUSED) return 0;
    printf("  %s: %s\n", label, rep.state == MOCAP_CALIBRATION_ACCEPTED ? "accepted" : "REFUSED");
    print_quality(&rep);
    if (rep.state != MOCAP_CALIBRATION_ACCEPTED) {
        printf("    reason: %s\n", rep.reason);
        *failed = 1;
    }
    *done = 1;
    return 1;
}

/* replay with the pose model: decode -> filter -> calibrate -> model -> drift correction. */
static int cmd_replay_pose(int argc, char **argv)
{
    const char *capture = argv[0];
    mocap_solver_config solver_config;
    if (solver_config_from_args(argc, argv, &solver_config) != 0) return 2;
    const char *model_arg = arg_value(argc, argv, "--model");
    const char *out_path = arg_value(argc, argv, "--out");
    const char *json_path = arg_value(argc, argv, "--json");
    const char *csv_path = arg_value(argc, argv, "--pose-csv");
    const char *truth_path = arg_value(argc, argv, "--truth");
    const char *metrics_path = arg_value(argc, argv, "--metrics-json");
    const char *cal_path = arg_value(argc, argv, "--calibration");
    const char *save_cal = arg_value(argc, argv, "--save-calibration");
    const char *prelude = arg_value(argc, argv, "--prelude");
    const char *order = arg_value(argc, argv, "--bvh-order");
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

    /* The solver consumes the frames, at the model's rate. */
    cli_refuse_options(argc, argv, "--csv", "(sensor frames) is not written with the pose model; use --pose-csv");
    cli_refuse_options(argc, argv, "--rate", "does not apply with the pose model: frames come at its rate");
    if (truth_path) {
        int cols = csv_first_row_columns(truth_path);
        if (cols < 0) {
            fprintf(stderr, "mocapctl: cannot open truth file %s\n", truth_path);
            return 1;
        }
        if (cols != POSE_TRUTH_COLS) {
            fprintf(stderr, "mocapctl: %s is not a pose truth (%d columns, expected %d: "
                    "`python3 -m training synth-capture` writes CAPTURE.truth.csv); a sensor "
                    "truth works without --model/--out/--json/--pose-csv\n",
                    truth_path, cols, POSE_TRUTH_COLS);
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
    if (open_model(model_arg, &model, &info) != 0) goto done;
    metrics = (pose_metrics *)calloc(1, sizeof *metrics);
    poses = (mocap_pose *)malloc(POSE_DRAIN * sizeof *poses);
    if (!metrics || !poses) goto done;

    if (out_path) {
        bvh_skeleton sk;
        s = bvh_skeleton_from_model_info(&info, &sk);
        if (s == MOCAP_OK) s = bvh_writer_open(out_path, &sk, 1.0 / info.frame_rate, bvh_order, &bvh);
        if (s != MOCAP_OK) {
            rc = fail(s, "writing BVH");
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
        write_pose_csv_header(csv, &info);
    }

    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    cfg.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(cfg.path, sizeof cfg.path, "%s", capture);
    cfg.replay_realtime = arg_flag(argc, argv, "--realtime");
    cfg.output_rate_hz = info.frame_rate;
    if (open_replay_session(capture, &cfg, prelude, cal_path, &session) != 0) goto done;
    int32_t character = -1;
    s = mocap_solver_open(model, &solver_config, &solver);
    if (s == MOCAP_OK) s = mocap_solver_add_character(solver, session, &character);
    if (s == MOCAP_OK) s = mocap_solver_start(solver);
    if (s == MOCAP_OK) s = mocap_session_start(session);
    if (s != MOCAP_OK) {
        rc = fail(s, "starting the solver");
        goto done;
    }
    printf("replay %s\n", capture);

    const long total_bytes = file_size(capture);
    const int tty = isatty(2);
    const int64_t start_ns = mocap_monotonic_ns();
    int64_t last_progress = start_ns;
    int last_decile = 0, progress_shown = 0;
    int heading_done = cal_path != NULL, tpose_done = cal_path != NULL, cal_failed = 0;
    uint64_t written = 0, in_motion = 0;
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
                rc = fail(MOCAP_ERR_IO, "writing BVH");
                goto done;
            }
            if (json) write_pose_json(json, p);
            if (csv) write_pose_csv(csv, p);
            pose_truth_row tr;
            if (truth.rows && pose_truth_at(&truth, p->time_s, &tr) == 0) {
                metrics_add(metrics, &info, p, &tr, info.frame_rate);
                in_motion += tr.motion != 0;
            }
        }
        report_step_once(session, MOCAP_CALIBRATION_HEADING, "heading step", &heading_done, &cal_failed);
        if (heading_done) report_step_once(session, MOCAP_CALIBRATION_TPOSE, "T-pose step", &tpose_done, &cal_failed);
        if (s == MOCAP_ERR_END_OF_STREAM || interrupted) break;
        if (s != MOCAP_OK && s != MOCAP_ERR_NO_DATA) {
            rc = fail(s, "solving");
            goto done;
        }
        int64_t now = mocap_monotonic_ns();
        if (total_bytes > 0 && now - last_progress > 500000000LL && now - start_ns > 1000000000LL) {
            mocap_session_stats stats;
            mocap_session_get_stats(session, &stats);
            double frac = (double)stats.bytes_received / (double)total_bytes;
            if (frac > 1) frac = 1;
            int decile = (int)(frac * 10);
            if (tty) {
                fprintf(stderr, "\r  %3.0f%% of %s, %llu poses ", 100 * frac, capture,
                        (unsigned long long)written);
                progress_shown = 1;
            } else if (decile > last_decile) {
                fprintf(stderr, "  %d%% of %s, %llu poses\n", decile * 10, capture,
                        (unsigned long long)written);
                last_decile = decile;
            }
            last_progress = now;
        }
        if (n == 0) mocap_sleep_ms(1);
    }
    if (progress_shown) fprintf(stderr, "\r%60s\r", "");
    if (!heading_done || !tpose_done)
        printf("  calibration: the capture ended before %s finished\n",
               !heading_done ? "the heading step" : "the T-pose step");
    const double wall = (double)(mocap_monotonic_ns() - start_ns) * 1e-9;

    if (save_cal && save_calibration(session, save_cal) != 0) goto done; /* rc is still 1 */
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
            rc = fail(s, "writing BVH");
            goto done;
        }
        printf("  wrote %s (BVH, SMPL-24 skeleton, metres, %s Euler, %llu frames at %.0f Hz)\n",
               out_path, bvh_order == BVH_ORDER_XYZ ? "XYZ" : "ZXY", (unsigned long long)written,
               info.frame_rate);
    }
    if (json && close_output(&json, json_path)) {
        rc = 1;
        goto done;
    }
    if (json_path) printf("  wrote %s (one JSON object per pose)\n", json_path);
    if (csv && close_output(&csv, csv_path)) {
        rc = 1;
        goto done;
    }
    if (csv_path) printf("  wrote %s (one CSV line per pose)\n", csv_path);
    if (truth.rows) metrics_print(metrics, truth_path);
    if (metrics_path && metrics_write_json(metrics, truth_path, metrics_path) != 0) goto done;
    if (metrics_path) printf("  wrote %s (the accuracy figures as JSON)\n", metrics_path);
    (void)in_motion;
    rc = (cal_failed || written == 0) ? 1 : 0;
    if (written == 0) fprintf(stderr, "mocapctl: no pose was solved (calibration %s)\n",
                              cal_failed ? "refused" : "missing");
    if (replay_ended_early(session)) rc = 1;
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
        free(metrics->pred_root);
        free(metrics->vel_root);
        free(metrics->true_root);
        free(metrics->times);
        free(metrics);
    }
    free(poses);
    free(truth.rows);
    return rc;
}

/* `mocapctl bench pipeline|latency|scaling|tip|all` (tools/bench.c). */
static int cmd_bench_model(const char *which, int argc, char **argv)
{
    static char model[4096], shipped[4096], root[4096];
    const char *model_arg = arg_value(argc, argv, "--model");
    int have_shipped = default_model_path(shipped, sizeof shipped) == 0;
    if (model_arg) {
        snprintf(model, sizeof model, "%s", model_arg);
    } else if (have_shipped) {
        snprintf(model, sizeof model, "%s", shipped);
    } else {
        fprintf(stderr, "mocapctl: no --model given and the shipped model was not found: %s\n", shipped);
        return 1;
    }
    mocapctl_bench_options o;
    memset(&o, 0, sizeof o);
    o.model_path = model;
    o.tip_model_path = arg_value(argc, argv, "--tip-model");
    if (have_shipped) {
        snprintf(root, sizeof root, "%s", shipped);
        char *cut = strstr(root, "/Packages/com.mocap.imu/");
        if (cut) {
            *cut = 0;
            o.repo_root = root;
        }
    }
    o.seconds = cli_number(argc, argv, "--seconds", 30.0, 0.1, 86400.0);
    o.latency_seconds = cli_number(argc, argv, "--latency-seconds", 10.0, 0.1, 86400.0);
    o.tip_seconds = cli_number(argc, argv, "--tip-seconds", 3.0, 0.1, 86400.0);
    o.threads = (int)cli_integer(argc, argv, "--threads", 1, 1, 256);
    o.max_characters = (int)cli_integer(argc, argv, "--max-characters", 32, 1, MOCAP_MAX_CHARACTERS);
    return mocapctl_bench_model(which, &o);
}

/* ---------------------------------------------------------------------------------------- */
/* live / record                                                                               */

static int open_live(int argc, char **argv, const char *record_path, float rate_hz,
                     mocap_session **out)
{
    const char *port = arg_value(argc, argv, "--port");
    if (!port) return usage();
    if (path_too_long(port, "port") || (record_path && path_too_long(record_path, "recording")))
        return 2;
    const char *baud = arg_value(argc, argv, "--baud");
    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    cfg.source_kind = MOCAP_SOURCE_SERIAL;
    snprintf(cfg.path, sizeof cfg.path, "%s", port);
    if (baud) cfg.baud = (uint32_t)cli_integer(argc, argv, "--baud", 0, 50, 16000000);
    if (record_path) snprintf(cfg.capture_path, sizeof cfg.capture_path, "%s", record_path);
    if (rate_hz > 0) cfg.output_rate_hz = rate_hz;
    mocap_status s = mocap_session_open(&cfg, out);
    if (s != MOCAP_OK) return fail(s, "opening the receiver");
    s = mocap_session_start(*out);
    if (s != MOCAP_OK) {
        mocap_session_close(*out);
        *out = NULL; /* callers close what they were handed on their own way out */
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

/* After calibration with --model: the solver consumes the session; prints the pose status
 * (fps, root height and position, foot contacts, flags) ten times a second. */
static int show_poses_until(mocap_session *session, mocap_model *model,
                            const mocap_solver_config *config, double limit_s)
{
    mocap_solver *solver = NULL;
    int32_t id = -1;
    mocap_status s = mocap_solver_open(model, config, &solver);
    if (s == MOCAP_OK) s = mocap_solver_add_character(solver, session, &id);
    if (s == MOCAP_OK) s = mocap_solver_start(solver);
    if (s != MOCAP_OK) {
        mocap_solver_close(solver);
        return fail(s, "starting the solver");
    }
    static mocap_pose poses[64];
    mocap_pose last;
    int have = 0;
    uint64_t count = 0, window_count = 0;
    int64_t start = mocap_monotonic_ns(), window_start = start, last_print = 0;
    double fps = 0;
    while (!interrupted && (double)(mocap_monotonic_ns() - start) * 1e-9 < limit_s) {
        uint32_t n = 0;
        mocap_solver_drain(solver, id, poses, 64, &n);
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

#define GUIDED_STEP_NO_FRAMES 2
#define NO_FRAMES_LIMIT_S 5.0

/* One calibration step with a countdown. 0 accepted, 1 refused or interrupted,
 * GUIDED_STEP_NO_FRAMES when the receiver delivered nothing (the window only opens with the
 * first frame, so without this a wrong port or baud rate would wait forever). */
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
    mocap_solver_config solver_config;
    if (solver_config_from_args(argc, argv, &solver_config) != 0) return 2;
    const char *record = arg_value(argc, argv, "--record");
    static const char *const live_outputs[] = {"--record", NULL};
    cli_refuse_overwriting(arg_value(argc, argv, "--port"), "serial port", argc, argv, live_outputs);
    /* Read before anything is opened: a bad value must not leave an empty capture behind. */
    const double limit = cli_number(argc, argv, "--seconds", 1e30, 0.001, 1e30);
    const int with_model = arg_value(argc, argv, "--model") != NULL || arg_flag(argc, argv, "--pose");
    if (!with_model) cli_refuse_options(argc, argv, "--smoothing", "applies to poses only (add --pose or --model)");
    mocap_model *model = NULL;
    mocap_model_info info;
    /* The model first: the session's output rate is the model's frame rate. */
    if (with_model && open_model(arg_value(argc, argv, "--model"), &model, &info) != 0) return 1;
    if (open_live(argc, argv, record, model ? info.frame_rate : 0.0f, &session) != 0) {
        mocap_model_close(model);
        return 1;
    }
    int rc = 0;
    for (int attempt = 0; attempt < 3; ++attempt) {
        rc = guided_step(session, MOCAP_CALIBRATION_HEADING,
                         "Heading step: lay all six sensors still on a flat surface, X axis (the "
                         "arrow) pointing where you will face, Z up.", 3.0f);
        if (rc == 0 || rc == GUIDED_STEP_NO_FRAMES || interrupted) break;
    }
    for (int attempt = 0; rc == 0 && attempt < 3; ++attempt) {
        rc = guided_step(session, MOCAP_CALIBRATION_TPOSE,
                         "T-pose step: strap the sensors on (pelvis, wrists, shins, head), face the "
                         "same way, arms straight out to the sides, stand still.", 3.0f);
        if (rc == 0 || rc == GUIDED_STEP_NO_FRAMES || interrupted) break;
    }
    if (rc == 0) printf("\nCalibrated. Streaming; Ctrl-C to stop.\n");
    if (rc == GUIDED_STEP_NO_FRAMES) {
        rc = 1; /* nothing arrives: showing an empty status would only wait */
    } else if (rc == 0 && model) {
        rc = show_poses_until(session, model, &solver_config, limit);
    } else {
        show_status_until(session, limit);
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

static int cmd_record(int argc, char **argv)
{
    const char *out = arg_value(argc, argv, "--out");
    /* Read before anything is opened: a bad value must not leave an empty capture behind. */
    const double limit = cli_number(argc, argv, "--seconds", 1e30, 0.001, 1e30);
    if (!out) return usage();
    static const char *const record_outputs[] = {"--out", NULL};
    cli_refuse_overwriting(arg_value(argc, argv, "--port"), "serial port", argc, argv, record_outputs);
    mocap_session *session = NULL;
    if (open_live(argc, argv, out, 0.0f, &session) != 0) return 1;
    printf("recording to %s; Ctrl-C to stop\n", out);
    show_status_until(session, limit);
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

/* ---------------------------------------------------------------------------------------- */
/* stream: poses -> VMC protocol (OSC over UDP), character i -> the i-th --vmc destination      */

#define STREAM_MAX 16

/* Every value of a repeated option, in order. */
static int arg_values(int argc, char **argv, const char *name, const char **out, int cap)
{
    int n = 0;
    for (int i = 0; i + 1 < argc; ++i) {
        if (strcmp(argv[i], name) == 0) {
            if (n == cap) return -1;
            out[n++] = argv[++i];
        }
    }
    return n;
}

static int cmd_stream(int argc, char **argv)
{
    const char *dests[STREAM_MAX], *replays[STREAM_MAX];
    int ndest = arg_values(argc, argv, "--vmc", dests, STREAM_MAX);
    int nrep = arg_values(argc, argv, "--replay", replays, STREAM_MAX);
    const char *port = arg_value(argc, argv, "--port");
    const char *rate = arg_value(argc, argv, "--rate");
    /* Read before anything is opened: a bad value must not leave an empty capture behind. */
    const double limit = cli_number(argc, argv, "--seconds", 1e30, 0.001, 1e30);
    const char *speed = arg_value(argc, argv, "--speed");
    const char *prelude = arg_value(argc, argv, "--prelude");
    mocap_solver_config solver_config;
    if (solver_config_from_args(argc, argv, &solver_config) != 0) return 2;
    if (ndest < 0 || nrep < 0) {
        fprintf(stderr, "mocapctl: at most %d --vmc and --replay\n", STREAM_MAX);
        return 2;
    }
    if (ndest == 0 || (nrep == 0) == (port == NULL)) {
        fprintf(stderr, "mocapctl stream: give --vmc HOST:PORT (e.g. 127.0.0.1:39539) and either "
                        "--replay CAPTURE or --port DEV\n");
        return usage();
    }
    if (port)
        cli_refuse_options(argc, argv, "--speed --realtime --prelude", "applies to --replay only");
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
    vopt.allow_remote = arg_flag(argc, argv, "--allow-remote");

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
            rc = fail(s, "VMC destination");
            goto done;
        }
    }
    if (open_model(arg_value(argc, argv, "--model"), &model, &info) != 0) goto done;
    poses = (mocap_pose *)malloc(POSE_DRAIN * sizeof *poses);
    if (!poses) goto done;

    if (port) {
        if (open_live(argc, argv, NULL, info.frame_rate, &sessions[0]) != 0) goto done;
        int cal = guided_step(sessions[0], MOCAP_CALIBRATION_HEADING,
                              "Heading step: lay all six sensors still on a flat surface, X axis "
                              "(the arrow) pointing where you will face, Z up.", 3.0f);
        if (cal == 0)
            cal = guided_step(sessions[0], MOCAP_CALIBRATION_TPOSE,
                              "T-pose step: strap the sensors on, face the same way, arms straight "
                              "out to the sides, stand still.", 3.0f);
        if (cal != 0) goto done;
    } else {
        for (int i = 0; i < nrep; ++i) {
            mocap_session_config cfg;
            mocap_config_defaults(&cfg);
            cfg.source_kind = MOCAP_SOURCE_REPLAY;
            snprintf(cfg.path, sizeof cfg.path, "%s", replays[i]);
            cfg.replay_realtime = arg_flag(argc, argv, "--realtime") || speed != NULL;
            if (speed) cfg.replay_speed = (float)cli_number(argc, argv, "--speed", 1.0, 0.01, 1000.0);
            cfg.output_rate_hz = info.frame_rate;
            if (open_replay_session(replays[i], &cfg, prelude, NULL, &sessions[i]) != 0) goto done;
        }
    }
    s = mocap_solver_open(model, &solver_config, &solver);
    for (int i = 0; s == MOCAP_OK && i < characters; ++i)
        s = mocap_solver_add_character(solver, sessions[i], &ids[i]);
    if (s == MOCAP_OK) s = mocap_solver_start(solver);
    for (int i = 0; !port && s == MOCAP_OK && i < characters; ++i) s = mocap_session_start(sessions[i]);
    if (s != MOCAP_OK) {
        rc = fail(s, "starting the solver");
        goto done;
    }
    for (int i = 0; i < characters; ++i)
        printf("character %d (%s) -> VMC %s, at most %g bundles/s\n", i, port ? port : replays[i],
               dests[i], (double)vopt.max_rate_hz);
    fflush(stdout);

    const int64_t start = mocap_monotonic_ns();
    uint64_t send_errors = 0;
    int running = characters;
    while (running > 0 && !interrupted &&
           (double)(mocap_monotonic_ns() - start) * 1e-9 < limit) {
        uint32_t total = 0;
        for (int i = 0; i < characters; ++i) {
            if (ended[i]) continue;
            uint32_t n = 0;
            s = mocap_solver_drain(solver, ids[i], poses, POSE_DRAIN, &n);
            for (uint32_t k = 0; k < n; ++k) {
                mocap_status vs = mocap_vmc_send_pose(vmc[i], &info, &poses[k]);
                if (vs != MOCAP_OK && vs != MOCAP_ERR_NO_DATA && send_errors++ < 5)
                    fprintf(stderr, "mocapctl: %s\n", mocap_last_error());
            }
            total += n;
            if (s == MOCAP_ERR_END_OF_STREAM) {
                ended[i] = 1;
                running--;
            } else if (s != MOCAP_OK && s != MOCAP_ERR_NO_DATA) {
                rc = fail(s, "solving");
                goto done;
            }
        }
        if (total == 0) mocap_sleep_ms(1);
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
        if (replay_ended_early(sessions[i])) rc = 1;
        report_capture_damage(sessions[i], replays[i]);
    }
    for (int i = 0; i < characters; ++i) {
        char what[32];
        snprintf(what, sizeof what, "character %d", i);
        report_dropped(sessions[i], solver, ids[i], what,
                       port ? "the machine could not keep up with the sensors"
                            : "a lower --speed (or none: an as-fast-as-possible replay waits "
                              "instead of dropping) streams every pose");
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

/* ---------------------------------------------------------------------------------------- */


/* The option list of `command` (NULL for an unknown command). */
static const char *options_of(const char *command)
{
    const size_t count = sizeof mocapctl_command_options / sizeof mocapctl_command_options[0];
    for (size_t i = 0; i < count; ++i)
        if (strcmp(mocapctl_command_options[i].command, command) == 0)
            return mocapctl_command_options[i].options;
    return NULL;
}

#if defined(_WIN32)
/* The command line as UTF-8, the encoding of the engine's paths: main's argv is in the ANSI code
 * page, where a file name outside it (say Japanese on a Western system) arrives as '?'. The
 * strings live until the process exits. NULL when Windows cannot give the wide command line. */
static char **utf8_arguments(int *argc)
{
    int n = 0;
    wchar_t **wide = CommandLineToArgvW(GetCommandLineW(), &n);
    if (!wide) return NULL;
    char **out = calloc((size_t)n + 1, sizeof *out);
    for (int i = 0; out && i < n; ++i) {
        int bytes = WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, NULL, 0, NULL, NULL);
        if (bytes <= 0 || !(out[i] = malloc((size_t)bytes))) { out = NULL; break; }
        WideCharToMultiByte(CP_UTF8, 0, wide[i], -1, out[i], bytes, NULL, NULL);
    }
    LocalFree(wide);
    if (out) *argc = n;
    return out;
}
#endif

int main(int argc, char **argv)
{
#if defined(_WIN32)
    {
        char **utf8 = utf8_arguments(&argc);
        if (!utf8) {
            fprintf(stderr, "mocapctl: could not read the command line as Unicode\n");
            return 2;
        }
        argv = utf8;
        /* Paths and names print as UTF-8; a console shows them right in this code page. */
        SetConsoleOutputCP(CP_UTF8);
    }
#endif
    if (argc < 2) return usage();
    signal(SIGINT, on_interrupt);
    const char *cmd = argv[1];
    if (strcmp(cmd, "help") == 0 || strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0)
        return print_usage(stdout, 0);
    /* The command's options: asked for help, or refused when the command does not take them. */
    const int bench_sub = strcmp(cmd, "bench") == 0 && argc >= 3;
    const char *name = bench_sub ? (strcmp(argv[2], "decode") == 0 ? "bench decode" : "bench") : cmd;
    const char *options = options_of(name);
    if (options) { /* bench's subcommand is a plain word: both checks pass over it */
        if (cli_asks_for_help(argc - 2, argv + 2, options)) return print_usage(stdout, 0);
        cli_refuse_unknown(name, argc - 2, argv + 2, options);
    }
    if (strcmp(cmd, "synth") == 0) return cmd_synth(argc - 2, argv + 2);
    if (strcmp(cmd, "replay") == 0) return cmd_replay(argc - 2, argv + 2);
    if (strcmp(cmd, "live") == 0) return cmd_live(argc - 2, argv + 2);
    if (strcmp(cmd, "record") == 0) return cmd_record(argc - 2, argv + 2);
    if (strcmp(cmd, "stream") == 0) return cmd_stream(argc - 2, argv + 2);
    if (strcmp(cmd, "infer") == 0 || strcmp(cmd, "model-info") == 0) return mocapctl_onnx(cmd, argc - 2, argv + 2);
    if (strcmp(cmd, "bench") == 0) {
        if (argc < 3) return usage();
        if (strcmp(argv[2], "decode") == 0) {
            double mbps = 0;
            return mocapctl_bench_decode(cli_number(argc - 3, argv + 3, "--seconds", 3.0, 0.1, 86400.0), &mbps);
        }
        return cmd_bench_model(argv[2], argc - 3, argv + 3);
    }
    if (strcmp(cmd, "version") == 0) {
        printf("mocapctl %s (API %d)\n", mocap_version_string(), mocap_api_version());
        return 0;
    }
    return usage();
}
