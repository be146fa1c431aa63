/* `mocapctl bench decode`: single-core throughput of the HiPNUC decoder on the packet the
 * 6-sensor wireless kit actually sends (0x62 with six 0x91 blocks, 470 bytes per frame). */
#include "bench.h"

#include "capture_file.h"
#include "error.h"
#include "hipnuc_decoder.h"
#include "platform.h"
#include "pose_limits.h"
#include "pose_range_table.h"
#include "sensor_set.h"
#include "solver.h"

#if defined(_WIN32)
#include <direct.h>
#else
#include <sys/stat.h>
#include <unistd.h>
#endif

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BENCH_NODES 6
#define BENCH_FRAMES 8192 /* ~3.9 MB: larger than typical L2, so the input streams from memory */
#define BENCH_CHUNK 4096  /* what a serial read typically returns */

typedef struct bench_counts {
    uint64_t frames;
    uint64_t samples;
    uint64_t bad_frames; /* frames that did not decode to BENCH_NODES samples */
} bench_counts;

static void count_frame(void *user, const hipnuc_frame *frame)
{
    bench_counts *c = user;
    c->frames++;
    c->samples += frame->sample_count;
    if (frame->sample_count != BENCH_NODES || frame->first_tag != HIPNUC_TAG_GWSOL) c->bad_frames++;
}

/* The next number of a linear congruential generator, in [0, 1) with 24 bits. */
static double next_uniform(uint32_t *rng)
{
    *rng = *rng * 1664525u + 1013904223u;
    return (double)(*rng >> 8) * (1.0 / 16777216.0);
}

/* Plausible, changing sensor values: a slow rotation about a tilted axis plus small noise, so
 * that no two frames are alike (a decoder must not benefit from repeated bytes). */
static void make_sample(uint32_t node, uint32_t frame, uint32_t *rng, hipnuc_sample *s)
{
    memset(s, 0, sizeof *s);
    s->node_id = node + 1;
    s->time_ms = frame * 10u;
    float angle = 0.01f * (float)frame + 0.7f * (float)node;
    float c = cosf(0.5f * angle), sn = sinf(0.5f * angle);
    s->quat[0] = c;
    s->quat[1] = 0.36f * sn;
    s->quat[2] = 0.48f * sn;
    s->quat[3] = 0.8f * sn;
    for (int i = 0; i < 3; i++) {
        float noise = (float)next_uniform(rng) - 0.5f;
        s->acc_g[i] = (i == 2 ? 1.0f : 0.0f) + 0.02f * noise;
        s->gyr_dps[i] = 30.0f * sinf(angle + (float)i) + noise;
        s->mag_ut[i] = 25.0f * cosf(angle - (float)i) + 0.3f * noise;
        s->euler_deg[i] = fmodf(57.29578f * angle * (float)(i + 1), 360.0f) - 180.0f;
    }
}

static mocap_status build_stream(uint8_t **out, size_t *size)
{
    const size_t payload_size = HIPNUC_GWSOL_HEADER_SIZE + BENCH_NODES * HIPNUC_IMUSOL_SIZE;
    const size_t frame_size = HIPNUC_HEADER_SIZE + payload_size;
    uint8_t *stream = malloc(frame_size * BENCH_FRAMES);
    if (!stream)
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "bench decode: cannot allocate %zu bytes",
                          frame_size * BENCH_FRAMES);
    uint32_t rng = 12345u;
    hipnuc_sample samples[BENCH_NODES];
    uint8_t *p = stream;
    for (uint32_t f = 0; f < BENCH_FRAMES; f++) {
        for (uint32_t n = 0; n < BENCH_NODES; n++) make_sample(n, f, &rng, &samples[n]);
        size_t payload = hipnuc_encode_gwsol((uint8_t)1, samples, BENCH_NODES,
                                             p + HIPNUC_HEADER_SIZE, payload_size);
        size_t framed = hipnuc_encode_frame(p + HIPNUC_HEADER_SIZE, payload, p, frame_size);
        if (payload != payload_size || framed != frame_size) {
            free(stream);
            return mocap_fail(MOCAP_ERR_STATE, "bench decode: encoder produced %zu/%zu bytes",
                              payload, framed);
        }
        p += frame_size;
    }
    *out = stream;
    *size = frame_size * BENCH_FRAMES;
    return MOCAP_OK;
}

int mocapctl_bench_decode(double seconds, double *mb_per_s)
{
    if (mb_per_s) *mb_per_s = 0.0;
    if (!(seconds > 0.0) || seconds > 3600.0) {
        mocap_status st = mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                                     "bench decode: --seconds must be in (0, 3600], got %g",
                                     seconds);
        fprintf(stderr, "%s\n", mocap_last_error());
        return st;
    }
    uint8_t *stream = NULL;
    size_t size = 0;
    mocap_status st = build_stream(&stream, &size);
    if (st != MOCAP_OK) {
        fprintf(stderr, "%s\n", mocap_last_error());
        return st;
    }

    /* The decoder holds a 2.4 KB buffer and a 2.7 KB frame: keep it off the stack. */
    hipnuc_decoder *decoder = malloc(sizeof *decoder);
    if (!decoder) {
        free(stream);
        st = mocap_fail(MOCAP_ERR_NO_MEMORY, "bench decode: cannot allocate the decoder");
        fprintf(stderr, "%s\n", mocap_last_error());
        return st;
    }
    hipnuc_decoder_init(decoder, HIPNUC_LAYOUT_AUTO);
    bench_counts counts = {0, 0, 0};
    uint64_t passes = 0;
    const int64_t start = mocap_monotonic_ns();
    const int64_t budget = (int64_t)(seconds * 1e9);
    int64_t elapsed = 0;
    do {
        for (size_t off = 0; off < size; off += BENCH_CHUNK) {
            size_t n = size - off < BENCH_CHUNK ? size - off : BENCH_CHUNK;
            hipnuc_decoder_feed(decoder, stream + off, n, count_frame, &counts);
        }
        passes++;
        elapsed = mocap_monotonic_ns() - start;
    } while (elapsed < budget);

    const uint64_t expected = passes * BENCH_FRAMES;
    const hipnuc_stats *stats = &decoder->stats;
    if (counts.frames != expected || counts.bad_frames != 0 ||
        counts.samples != expected * BENCH_NODES || stats->crc_failures != 0 ||
        stats->bytes_skipped != 0 || decoder->length != 0) {
        st = mocap_fail(MOCAP_ERR_STATE,
                        "bench decode: decoded %llu frames (%llu malformed, %llu samples, %llu CRC "
                        "failures, %llu bytes skipped), expected %llu frames",
                        (unsigned long long)counts.frames, (unsigned long long)counts.bad_frames,
                        (unsigned long long)counts.samples,
                        (unsigned long long)stats->crc_failures,
                        (unsigned long long)stats->bytes_skipped, (unsigned long long)expected);
        fprintf(stderr, "%s\n", mocap_last_error());
    } else {
        const double secs = (double)elapsed * 1e-9;
        const double mbps = (double)size * (double)passes / secs / 1e6;
        const double fps = (double)counts.frames / secs;
        printf("decode: %.0f MB/s (%.0f frames/s), %d-node 0x62 frames, one core\n", mbps, fps,
               BENCH_NODES);
        if (mb_per_s) *mb_per_s = mbps;
    }
    free(decoder);
    free(stream);
    return st;
}

/* ========================================================================================== */
/* `mocapctl bench pipeline|latency|scaling|tip|all`: the engine with the pose model.          */

#include "mocap_math.h"
#include "onnx_generic.h"
#include "onnx_runtime.h"
#include "synth.h"

#if defined(__linux__)
#include <errno.h>
#include <fcntl.h>
#include <pty.h>
#include <time.h>
#include <unistd.h>
#define BENCH_HAVE_PTY 1
#endif

#define POSES_CAP 512
#define TIP_WINDOW 40
#define TIP_IN 221
#define TIP_OUT 131

static int bench_fail(mocap_status st, const char *what)
{
    fprintf(stderr, "mocapctl bench: %s: %s (%s)\n", what, mocap_last_error(), mocap_status_name(st));
    return 1;
}

#if defined(BENCH_HAVE_PTY)
/* CPU time this process has used, every thread together. */
static double process_cpu_seconds(void)
{
    struct timespec t;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t) != 0) return 0;
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}
#endif

/* Peak and current resident set (MB), from /proc/self/status; -1 elsewhere. */
static void rss_mb(double *hwm, double *rss)
{
    *hwm = *rss = -1;
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return;
    char line[256];
    while (fgets(line, sizeof line, f)) {
        long kb;
        if (sscanf(line, "VmHWM: %ld kB", &kb) == 1) *hwm = kb / 1024.0;
        if (sscanf(line, "VmRSS: %ld kB", &kb) == 1) *rss = kb / 1024.0;
    }
    fclose(f);
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return x < y ? -1 : x > y;
}

static double percentile_ms(int64_t *v, size_t n, double p)
{
    if (!n) return NAN;
    qsort(v, n, sizeof *v, cmp_i64);
    size_t i = (size_t)ceil(p * (double)n);
    if (i > 0) i--;
    if (i >= n) i = n - 1;
    return (double)v[i] * 1e-6;
}

typedef struct bench_ctx {
    const mocapctl_bench_options *o;
    char dir[200];
    char capture[240];       /* calibration prelude + motion, for replays */
    mocap_calibration cal;   /* from one replay of it */
    mocap_model *model;
    mocap_model_info info;
    double pipeline_fps;     /* poses/s of one character (0 until measured) */
    uint32_t sensors;        /* in the generated capture */
} bench_ctx;

/* The benchmark's sensor set into a session config, with the model's optional sensors. */
static void use_sensor_set(const bench_ctx *b, mocap_session_config *cfg)
{
    if (b->o->sensor_count > 0) {
        cfg->sensor_count = b->o->sensor_count;
        for (uint32_t i = 0; i < b->o->sensor_count; ++i) {
            cfg->sensor_segments[i] = b->o->sensor_segments[i];
            cfg->node_ids[i] = b->o->node_ids[i];
        }
        cfg->optional_mask = b->o->optional_mask;
    }
    sensor_set_apply_model(cfg, &b->info);
}

static mocap_status make_capture(bench_ctx *b)
{
    synth_config cfg;
    synth_config_defaults(&cfg);
    mocap_session_config set;
    mocap_config_defaults(&set);
    use_sensor_set(b, &set);
    cfg.sensor_count = set.sensor_count;
    for (uint32_t i = 0; i < set.sensor_count; ++i) {
        cfg.segments[i] = set.sensor_segments[i];
        cfg.node_ids[i] = set.node_ids[i];
    }
    cfg.seed = 11;
    cfg.motion_s = b->o->seconds;
    cfg.acc_noise_g = 0.01;
    cfg.gyr_noise_dps = 0.3;
    cfg.quat_noise_deg = 0.3;
    cfg.acc_bias_g = 0.01;
    cfg.still_tremor_deg = 0.2;
    snprintf(b->capture, sizeof b->capture, "%s/bench.cap", b->dir);
    return synth_write_capture(&cfg, synth_builtin_motion("mixed"), NULL, b->capture, NULL);
}

static mocap_status open_replay(bench_ctx *b, int with_calibration, mocap_session **out)
{
    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    use_sensor_set(b, &cfg);
    cfg.source_kind = MOCAP_SOURCE_REPLAY;
    snprintf(cfg.path, sizeof cfg.path, "%.240s", b->capture);
    cfg.output_rate_hz = b->info.frame_rate;
    mocap_status st = mocap_session_open(&cfg, out);
    if (st == MOCAP_OK && with_calibration) st = mocap_calibration_set(*out, &b->cal);
    return st;
}

/* One plain replay of the capture, calibrating on its prelude (synth's layout). */
static mocap_status calibrate_once(bench_ctx *b)
{
    capture_reader *r = NULL;
    mocap_status st = capture_reader_open(b->capture, &r);
    if (st != MOCAP_OK) return st;
    int64_t ns;
    const uint8_t *data;
    size_t len;
    st = capture_reader_next(r, &ns, &data, &len);
    capture_reader_close(r);
    if (st != MOCAP_OK) return st;
    const double t0 = (double)ns * 1e-9;
    mocap_session *s = NULL;
    st = open_replay(b, 0, &s);
    if (st == MOCAP_OK) st = mocap_calibration_schedule(s, MOCAP_CALIBRATION_HEADING, t0 + 0.5, 2.0f);
    if (st == MOCAP_OK) st = mocap_calibration_schedule(s, MOCAP_CALIBRATION_TPOSE, t0 + 5.5, 2.0f);
    if (st == MOCAP_OK) st = mocap_session_start(s);
    static mocap_frame frames[64];
    while (st == MOCAP_OK) {
        uint32_t n = 0;
        mocap_status d = mocap_session_drain(s, frames, 64, &n);
        if (d == MOCAP_ERR_END_OF_STREAM) break;
        if (n == 0) mocap_sleep_ms(1);
    }
    if (st == MOCAP_OK) st = mocap_calibration_get(s, &b->cal);
    mocap_calibration_report rep;
    if (st == MOCAP_OK) st = mocap_calibration_get_step_report(s, MOCAP_CALIBRATION_TPOSE, &rep);
    if (st == MOCAP_OK && rep.state != MOCAP_CALIBRATION_ACCEPTED)
        st = mocap_fail(MOCAP_ERR_BAD_CALIBRATION, "bench: the capture's calibration was refused: %s",
                        rep.reason);
    mocap_session_close(s);
    return st;
}

/* Replays the capture for `characters` characters through one solver, as fast as possible,
 * calibrated from the first frame. Returns poses per second per character. */
static mocap_status run_characters(bench_ctx *b, int characters, double *per_char_fps,
                                   double *wall_s, uint64_t *poses_total, double *model_us)
{
    mocap_session *sessions[MOCAP_MAX_CHARACTERS] = {0};
    int32_t ids[MOCAP_MAX_CHARACTERS];
    int ended[MOCAP_MAX_CHARACTERS] = {0};
    mocap_solver *solver = NULL;
    mocap_pose *poses = (mocap_pose *)malloc(POSES_CAP * sizeof *poses);
    if (!poses) return mocap_fail(MOCAP_ERR_NO_MEMORY, "bench: out of memory");
    mocap_status st = mocap_solver_open(b->model, NULL, &solver);
    for (int c = 0; st == MOCAP_OK && c < characters; ++c) {
        st = open_replay(b, 1, &sessions[c]);
        if (st == MOCAP_OK) st = mocap_solver_add_character(solver, sessions[c], &ids[c]);
    }
    if (st == MOCAP_OK) st = mocap_solver_start(solver);
    const int64_t t0 = mocap_monotonic_ns();
    for (int c = 0; st == MOCAP_OK && c < characters; ++c) st = mocap_session_start(sessions[c]);
    uint64_t total = 0;
    int remaining = characters;
    while (st == MOCAP_OK && remaining > 0) {
        int got_any = 0;
        for (int c = 0; c < characters; ++c) {
            if (ended[c]) continue;
            uint32_t n = 0;
            mocap_status d = mocap_solver_drain(solver, ids[c], poses, POSES_CAP, &n);
            total += n;
            got_any |= n > 0;
            if (d == MOCAP_ERR_END_OF_STREAM) {
                ended[c] = 1;
                remaining--;
            } else if (d != MOCAP_OK && d != MOCAP_ERR_NO_DATA) {
                st = d;
            }
        }
        if (!got_any) mocap_sleep_ms(1);
    }
    const double wall = (double)(mocap_monotonic_ns() - t0) * 1e-9;
    if (model_us && solver) {
        mocap_solver_stats ss;
        if (mocap_solver_get_stats(solver, -1, &ss) == MOCAP_OK && ss.ticks)
            *model_us = (double)ss.run_ns_total / (double)ss.ticks * 1e-3;
    }
    if (solver) mocap_solver_close(solver);
    for (int c = 0; c < characters; ++c) mocap_session_close(sessions[c]);
    free(poses);
    if (st != MOCAP_OK) return st;
    *wall_s = wall;
    *poses_total = total;
    *per_char_fps = wall > 0 ? (double)total / characters / wall : 0;
    return MOCAP_OK;
}

/* A unit quaternion from next_uniform: uniform enough on the sphere for a worst case. */
static void random_rotation(uint32_t *rng, double q[4])
{
    double n = 0.0;
    for (int i = 0; i < 4; ++i) {
        q[i] = next_uniform(rng) - 0.5;
        n += q[i] * q[i];
    }
    n = sqrt(n);
    for (int i = 0; i < 4; ++i) q[i] /= n;
}

/* Time per pose of the pose limits at 25 deg: joints wandering slowly through their range (what
 * a model's output does; the guard checks the point it found last) and a pose of random joints,
 * nearly all outside the range (each joint scans its whole span: the worst case). */
static void bench_pose_limits(void)
{
    enum { POSES = 4000 };
    pose_limits_state state;
    pose_limits_reset(&state);
    double q[POSE_LIMITS_JOINTS][4];
    uint32_t rng = 0x9E3779B9u;
    long turned = 0;
    int64_t t0 = mocap_monotonic_ns();
    for (int t = 0; t < POSES; ++t) {
        for (int j = 0; j < POSE_LIMITS_JOINTS; ++j) {
            const pose_range_span *span = &pose_range_joints[j];
            if (span->count == 0) {
                q[j][0] = 1.0; q[j][1] = q[j][2] = q[j][3] = 0.0;
                continue;
            }
            /* a new point of the range every second, a little off it in between */
            const int8_t *v = pose_range_points[span->first + (uint32_t)(t / 60 + j) % span->count];
            double n = 0.0;
            for (int i = 0; i < 4; ++i) {
                q[j][i] = v[i] + 3.0 * sin(0.05 * t + i + j);
                n += q[j][i] * q[j][i];
            }
            for (int i = 0; i < 4; ++i) q[j][i] /= sqrt(n);
        }
        turned += pose_limits_apply(&state, 25.0, q, NULL);
    }
    const double near_us = (double)(mocap_monotonic_ns() - t0) / POSES / 1000.0;
    long far_turned = 0;
    t0 = mocap_monotonic_ns();
    for (int t = 0; t < POSES; ++t) {
        for (int j = 0; j < POSE_LIMITS_JOINTS; ++j) random_rotation(&rng, q[j]);
        far_turned += pose_limits_apply(&state, 25.0, q, NULL);
    }
    const double far_us = (double)(mocap_monotonic_ns() - t0) / POSES / 1000.0;
    printf("pose limits (--pose-limits 25): %.2f us per pose with its joints moving through their "
           "range (%ld of %d joint-poses turned back), %.1f us with every joint random (%.1f "
           "turned back per pose, each a scan of its joint's range), one core\n",
           near_us, turned, POSES * (POSE_LIMITS_JOINTS - 1), far_us, (double)far_turned / POSES);
}

static int bench_pipeline(bench_ctx *b)
{
    double fps = 0, wall = 0, model_us = 0, hwm, rss;
    uint64_t poses = 0;
    mocap_status st = run_characters(b, 1, &fps, &wall, &poses, &model_us);
    if (st != MOCAP_OK) return bench_fail(st, "pipeline");
    b->pipeline_fps = fps;
    rss_mb(&hwm, &rss);
    printf("pipeline: %.0f frames/s per character end to end on replay (%llu poses of a %.0f s "
           "capture in %.2f s: decode -> filter -> calibrate -> model -> drift; model run %.0f us "
           "per frame)  [goal >= 2000]\n",
           fps, (unsigned long long)poses, (double)poses / b->info.frame_rate, wall, model_us);
    printf("memory: peak RSS %.0f MB (VmHWM; now %.0f MB) after one character, model loaded  "
           "[goal <= 150]\n", hwm, rss);
    bench_pose_limits();
    return 0;
}

#if defined(BENCH_HAVE_PTY)
typedef struct pty_writer {
    int fd;
    const char *capture;
    double skip_s, seconds;
    volatile int stop;
    volatile int64_t done_ns; /* when the last byte was written (0 before) */
    mocap_status status;
} pty_writer;

static void sleep_until(int64_t t_ns)
{
    for (;;) {
        int64_t now = mocap_monotonic_ns();
        if (now >= t_ns) return;
        struct timespec ts = {(time_t)((t_ns - now) / 1000000000LL), (long)((t_ns - now) % 1000000000LL)};
        nanosleep(&ts, NULL);
    }
}

/* Writes the capture's records into the pty at their recorded pace (100 Hz packets), from
 * skip_s into it, for `seconds`. */
static void pty_writer_main(void *arg)
{
    pty_writer *w = (pty_writer *)arg;
    capture_reader *r = NULL;
    w->status = capture_reader_open(w->capture, &r);
    if (w->status != MOCAP_OK) return;
    int64_t first = -1, start = 0;
    int64_t ns;
    const uint8_t *data;
    size_t len;
    while (!w->stop && capture_reader_next(r, &ns, &data, &len) == MOCAP_OK) {
        if (first < 0) first = ns;
        double t = (double)(ns - first) * 1e-9;
        if (t < w->skip_s) continue;
        if (t > w->skip_s + w->seconds) break;
        if (!start) start = mocap_monotonic_ns() - (int64_t)((t - w->skip_s) * 1e9);
        sleep_until(start + (int64_t)((t - w->skip_s) * 1e9));
        /* The fd is non-blocking: a session that stopped reading fills the pty, and a blocked
         * write would keep this thread (and the join) waiting forever. */
        size_t off = 0;
        while (off < len && !w->stop) {
            ssize_t n = write(w->fd, data + off, len - off);
            if (n > 0) {
                off += (size_t)n;
            } else if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) {
                mocap_sleep_ms(1);
            } else {
                break;
            }
        }
    }
    w->done_ns = mocap_monotonic_ns();
    capture_reader_close(r);
}
#endif

/* Latency from byte arrival to pose: a live serial session on a pseudo-terminal fed at the
 * capture's 100 Hz pace. */
static int bench_latency(bench_ctx *b)
{
#if !defined(BENCH_HAVE_PTY)
    printf("latency: skipped (needs a pseudo-terminal; Linux only)\n");
    return 0;
#else
    int master = -1, slave = -1;
    char name[256];
    if (openpty(&master, &slave, name, NULL, NULL) != 0) {
        printf("latency: skipped (openpty failed)\n");
        return 0;
    }
    fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK); /* see pty_writer_main */
    const double seconds = b->o->latency_seconds > 0 ? b->o->latency_seconds : 10.0;
    mocap_session_config cfg;
    mocap_config_defaults(&cfg);
    use_sensor_set(b, &cfg);
    cfg.source_kind = MOCAP_SOURCE_SERIAL;
    snprintf(cfg.path, sizeof cfg.path, "%s", name);
    cfg.output_rate_hz = b->info.frame_rate;
    cfg.auto_reconnect = 0;
    mocap_session *session = NULL;
    mocap_solver *solver = NULL;
    int32_t id = -1;
    size_t cap = (size_t)(seconds * b->info.frame_rate * 2 + 64), n_lat = 0;
    int64_t *lat = (int64_t *)malloc(cap * sizeof *lat);
    mocap_pose *poses = (mocap_pose *)malloc(POSES_CAP * sizeof *poses);
    mocap_status st = (lat && poses) ? mocap_session_open(&cfg, &session) : MOCAP_ERR_NO_MEMORY;
    if (st == MOCAP_OK) st = mocap_calibration_set(session, &b->cal);
    if (st == MOCAP_OK) st = mocap_solver_open(b->model, NULL, &solver);
    if (st == MOCAP_OK) st = mocap_solver_add_character(solver, session, &id);
    if (st == MOCAP_OK) st = mocap_solver_start(solver);
    if (st == MOCAP_OK) st = mocap_session_start(session);
    pty_writer w = {master, b->capture, 8.0, seconds, 0, 0, MOCAP_OK};
    mocap_thread *thread = NULL;
    if (st == MOCAP_OK && mocap_thread_start(&thread, pty_writer_main, &w, "bench-pty") != 0)
        st = mocap_fail(MOCAP_ERR_STATE, "bench: cannot start the writer thread");
    const int64_t live_start = mocap_monotonic_ns();
    const int64_t end = live_start + (int64_t)((seconds + 1.0) * 1e9);
    const double cpu_start = process_cpu_seconds();
    while (st == MOCAP_OK && mocap_monotonic_ns() < end) {
        uint32_t n = 0;
        mocap_solver_drain(solver, id, poses, POSES_CAP, &n);
        for (uint32_t i = 0; i < n && n_lat < cap; ++i) {
            /* The first second is warm-up (threads, ONNX Runtime's first runs): not counted. */
            if (poses[i].sequence < (uint64_t)b->info.frame_rate) continue;
            /* Once the input has stopped, a live session still releases (held) frames by wall
             * time: those measure the silence, not the engine. */
            const int64_t done = w.done_ns;
            if (done && poses[i].frame_emitted_ns > done) continue;
            if (poses[i].newest_receive_ns > 0)
                lat[n_lat++] = poses[i].pose_emitted_ns - poses[i].newest_receive_ns;
        }
        if (!n) mocap_sleep_ms(1);
    }
    const double cpu_share = (process_cpu_seconds() - cpu_start) /
                             ((double)(mocap_monotonic_ns() - live_start) * 1e-9);
    w.stop = 1;
    if (thread) mocap_thread_join(thread);
    if (solver) mocap_solver_close(solver);
    if (session) mocap_session_close(session);
    close(master);
    close(slave);
    int rc = 0;
    if (st != MOCAP_OK) {
        rc = bench_fail(st, "latency");
    } else if (n_lat < 10) {
        printf("latency: only %zu poses came out of the pseudo-terminal session\n", n_lat);
        rc = 1;
    } else {
        double p50 = percentile_ms(lat, n_lat, 0.50), p99 = percentile_ms(lat, n_lat, 0.99);
        double mx = (double)lat[n_lat - 1] * 1e-6;
        printf("latency: byte arrival -> pose available p50 %.2f ms, p99 %.2f ms, max %.2f ms "
               "(%zu poses after a 1 s warm-up, live serial session on a pty fed at 100 Hz)  "
               "[goal p99 < 5]\n",
               p50, p99, mx, n_lat);
        mocap_model_options mo;   /* the bench opens its model with the defaults */
        mocap_model_options_defaults(&mo);
        printf("cpu: the process used %.0f %% of one core while live (engine threads, the pty "
               "writer and this polling loop; ONNX Runtime intra-op threads %d, the default)\n",
               100.0 * cpu_share, mo.intra_op_threads);
    }
    free(lat);
    free(poses);
    return rc;
#endif
}

static int bench_scaling(bench_ctx *b)
{
    static const int counts[] = {1, 2, 4, 8, 16, 32};
    printf("scaling (one solver, batched; replay as fast as possible):\n");
    for (size_t i = 0; i < sizeof counts / sizeof counts[0]; ++i) {
        int n = counts[i];
        if (n > b->o->max_characters) break;
        double fps = 0, wall = 0, model_us = 0, hwm, rss;
        uint64_t poses = 0;
        mocap_status st = run_characters(b, n, &fps, &wall, &poses, &model_us);
        if (st != MOCAP_OK) return bench_fail(st, "scaling");
        rss_mb(&hwm, &rss);
        printf("  %2d characters: %7.0f frames/s per character, %7.0f in all, %.2f s, model run "
               "%.0f us per batched call, RSS %.0f MB%s\n",
               n, fps, fps * n, wall, model_us, rss, n == 32 ? "  [goal >= 60 per character]" : "");
    }
    return 0;
}

static int python_has_torch(const char *py)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "\"%s\" -c \"import torch, onnx\" >/dev/null 2>&1", py);
    return system(cmd) == 0;
}

/* The TIP-shaped network: --tip-model, $MOCAP_TIP_MODEL, or made now with the training CLI. */
static int tip_model_path(bench_ctx *b, char *out, size_t cap)
{
    const char *p = b->o->tip_model_path ? b->o->tip_model_path : getenv("MOCAP_TIP_MODEL");
    if (p && p[0]) {
        snprintf(out, cap, "%s", p);
        return 0;
    }
    if (!b->o->repo_root) {
        fprintf(stderr, "mocapctl bench tip: no --tip-model and the repository (training/) was not "
                        "found to make one\n");
        return -1;
    }
    const char *candidates[3] = {getenv("MOCAP_PYTHON"), "/usr/bin/python3", "python3"};
    const char *py = NULL;
    for (int i = 0; i < 3 && !py; ++i)
        if (candidates[i] && candidates[i][0] && python_has_torch(candidates[i])) py = candidates[i];
    if (!py) {
        fprintf(stderr, "mocapctl bench tip: no python3 with torch and onnx to run `python3 -m "
                        "training tip-model` (or pass --tip-model FILE)\n");
        return -1;
    }
    snprintf(out, cap, "%s/tip_shaped.onnx", b->dir);
    char cmd[3000];
    snprintf(cmd, sizeof cmd, "cd \"%s\" && \"%s\" -m training tip-model --out \"%s\" >/dev/null",
             b->o->repo_root, py, out);
    if (system(cmd) != 0) {
        fprintf(stderr, "mocapctl bench tip: `%s` failed\n", cmd);
        return -1;
    }
    return 0;
}

/* The shipped precisions of the pose model, found beside --model by their file names; --model
 * itself is always measured (first) even when it is none of them. */
#define PRECISION_MAX 4
typedef struct timed_model {
    char path[1024];
    char label[16];
    ort_model *model;
    ort_stream *stream;
    int64_t *t;
    size_t n;
} timed_model;

static int find_precisions(const char *model_path, timed_model *out)
{
    static const char *const names[] = {"fp32", "fp16", "int8"};
    int count = 0;
    snprintf(out[count].path, sizeof out[count].path, "%s", model_path);
    snprintf(out[count].label, sizeof out[count].label, "--model");
    count++;
    const char *slash = strrchr(model_path, '/');
#if defined(_WIN32)
    const char *back = strrchr(model_path, '\\');
    if (!slash || (back && back > slash)) slash = back;
#endif
    const size_t dir_len = slash ? (size_t)(slash - model_path + 1) : 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0] && count < PRECISION_MAX; ++i) {
        char path[1024];
        snprintf(path, sizeof path, "%.*smocap_pose_%s.onnx", (int)dir_len, model_path, names[i]);
        FILE *f = mocap_fopen(path, "rb");
        if (!f) continue;
        fclose(f);
        if (strcmp(path, model_path) == 0) {
            snprintf(out[0].label, sizeof out[0].label, "%s", names[i]);
            continue;
        }
        snprintf(out[count].path, sizeof out[count].path, "%s", path);
        snprintf(out[count].label, sizeof out[count].label, "%s", names[i]);
        count++;
    }
    return count;
}

/* A still T-pose with small accelerations, every sensor present (the mask all ones). */
static void fill_still_inputs(ort_model *m, ort_stream *stream)
{
    const int n = ort_model_get_info(m)->sensor_count;
    float *ori = ort_stream_orientation(stream), *acc = ort_stream_acceleration(stream);
    float *mask = ort_stream_mask(stream);
    for (int s = 0; s < n; ++s) {
        for (int k = 0; k < 9; ++k) ori[s * 9 + k] = (k % 4 == 0) ? 1.0f : 0.0f;
        for (int k = 0; k < 3; ++k) acc[s * 3 + k] = 0.1f * (float)(s + k);
        if (mask) mask[s] = 1.0f;
    }
}

static void close_timed(timed_model *ms, int count)
{
    for (int i = 0; i < count; ++i) {
        ort_stream_destroy(ms[i].stream);
        ort_model_close(ms[i].model);
        free(ms[i].t);
    }
}

/* Our model(s) the way the solver runs them: one character, T = 1, state carried. The models
 * take turns in short rounds, so a busy moment of the machine falls on all of them alike. */
static mocap_status time_our_models(bench_ctx *b, timed_model *ms, int count, double seconds)
{
    ort_options oo;
    ort_options_defaults(&oo);
    oo.intra_op_threads = b->o->threads;
    const size_t cap = 200000;
    for (int i = 0; i < count; ++i) {
        mocap_status st = ort_model_open(ms[i].path, &oo, &ms[i].model);
        if (st == MOCAP_OK) st = ort_stream_create(ms[i].model, 1, 1, &ms[i].stream);
        if (st != MOCAP_OK) return st;
        ms[i].t = (int64_t *)malloc(cap * sizeof(int64_t));
        if (!ms[i].t) return mocap_fail(MOCAP_ERR_NO_MEMORY, "bench: timing buffers");
        fill_still_inputs(ms[i].model, ms[i].stream);
        for (int w = 0; w < 20; ++w) ort_stream_run(ms[i].stream); /* warm-up */
    }
    const int rounds = 10;
    for (int r = 0; r < rounds; ++r) {
        for (int i = 0; i < count; ++i) {
            const int64_t end = mocap_monotonic_ns() + (int64_t)(seconds / rounds * 1e9);
            while (ms[i].n < cap && mocap_monotonic_ns() < end) {
                int64_t a = mocap_monotonic_ns();
                mocap_status st = ort_stream_run(ms[i].stream);
                if (st != MOCAP_OK) return st;
                ms[i].t[ms[i].n++] = mocap_monotonic_ns() - a;
            }
        }
    }
    return MOCAP_OK;
}

static double mean_ms(const int64_t *t, size_t n)
{
    double sum = 0;
    for (size_t i = 0; i < n; ++i) sum += (double)t[i];
    return n ? sum / (double)n * 1e-6 : 0.0;
}

static int bench_tip(bench_ctx *b)
{
    char path[1024];
    if (tip_model_path(b, path, sizeof path) != 0) return 1;
    const int threads = b->o->threads;
    const double seconds = b->o->tip_seconds > 0 ? b->o->tip_seconds : 3.0;

    timed_model ours[PRECISION_MAX];
    memset(ours, 0, sizeof ours);
    const int n_models = find_precisions(b->o->model_path, ours);
    mocap_status st = time_our_models(b, ours, n_models, seconds);
    if (st != MOCAP_OK) {
        close_timed(ours, n_models);
        return bench_fail(st, "running our model");
    }

    size_t cap = 200000, n_tip = 0;
    int64_t *t_tip = (int64_t *)malloc(cap * sizeof(int64_t));
    if (!t_tip) {
        close_timed(ours, n_models);
        return bench_fail(MOCAP_ERR_NO_MEMORY, "tip");
    }
    /* TIP's way: the whole 40-frame window re-run for every output frame, the newest frame's
     * input holding the previous output (its 131-value state feedback). */
    ort_generic *tip = NULL;
    st = ort_generic_open(path, threads, &tip);
    if (st == MOCAP_OK && (ort_generic_input_count(tip) != (size_t)TIP_WINDOW * TIP_IN ||
                           ort_generic_output_count(tip) != (size_t)TIP_WINDOW * TIP_OUT))
        st = mocap_fail(MOCAP_ERR_FORMAT, "%s: expected input [1,%d,%d] and output [1,%d,%d]", path,
                        TIP_WINDOW, TIP_IN, TIP_WINDOW, TIP_OUT);
    if (st != MOCAP_OK) {
        ort_generic_close(tip);
        close_timed(ours, n_models);
        free(t_tip);
        return bench_fail(st, "opening the TIP-shaped model");
    }
    float *in = ort_generic_input(tip);
    const float *out = ort_generic_output(tip);
    mocap_rng rng;
    mocap_rng_seed(&rng, 3);
    for (size_t k = 0; k < (size_t)TIP_WINDOW * TIP_IN; ++k) in[k] = (float)(mocap_rng_gaussian(&rng) * 0.5);
    for (int i = 0; i < 5 && st == MOCAP_OK; ++i) st = ort_generic_run(tip); /* warm-up */
    int64_t end = mocap_monotonic_ns() + (int64_t)(seconds * 1e9);
    while (st == MOCAP_OK && n_tip < cap && mocap_monotonic_ns() < end) {
        int64_t a = mocap_monotonic_ns();
        memmove(in, in + TIP_IN, (size_t)(TIP_WINDOW - 1) * TIP_IN * sizeof(float));
        float *newest = in + (size_t)(TIP_WINDOW - 1) * TIP_IN;
        for (int k = 0; k < 90; ++k) newest[k] = (float)(mocap_rng_gaussian(&rng) * 0.5);
        memcpy(newest + 90, out + (size_t)(TIP_WINDOW - 1) * TIP_OUT, TIP_OUT * sizeof(float));
        st = ort_generic_run(tip);
        t_tip[n_tip++] = mocap_monotonic_ns() - a;
    }
    ort_generic_close(tip);
    int rc = 0;
    if (st != MOCAP_OK) {
        rc = bench_fail(st, "running the TIP-shaped model");
    } else {
        const double tip_p50 = percentile_ms(t_tip, n_tip, 0.5), tip_mean = mean_ms(t_tip, n_tip);
        printf("tip: the seed's approach (TIP-shaped net, 221 -> 256, 4 x 16-head causal "
               "transformer, FF 1024, RNN 512 -> 131, random weights) re-run over a %d-frame "
               "window per output frame, same ONNX Runtime %s, %d intra-op thread(s):\n",
               TIP_WINDOW, ort_library_version(), threads);
        printf("  TIP-shaped: %.3f ms per frame (p50 %.3f; %zu frames) = %.0f frames/s per character\n",
               tip_mean, tip_p50, n_tip, 1e3 / tip_mean);
        printf("  ours, model only (one character, T = 1, recurrent state; the precisions take turns):\n");
        printf("    %-8s %9s %9s %9s %10s %8s  %s\n", "weights", "mean ms", "p50 ms", "p99 ms",
               "frames/s", "vs TIP", "file");
        for (int i = 0; i < n_models; ++i) {
            const double m = mean_ms(ours[i].t, ours[i].n);
            printf("    %-8s %9.3f %9.3f %9.3f %10.0f %7.1fx  %s\n", ours[i].label, m,
                   percentile_ms(ours[i].t, ours[i].n, 0.5), percentile_ms(ours[i].t, ours[i].n, 0.99),
                   1e3 / m, tip_mean / m, ours[i].path);
        }
        const double ours_mean = mean_ms(ours[0].t, ours[0].n);
        printf("  ratio per character (--model): %.1fx (model vs model)", tip_mean / ours_mean);
        if (b->pipeline_fps > 0)
            printf(", %.1fx (our whole pipeline vs the TIP network alone)",
                   b->pipeline_fps / (1e3 / tip_mean));
        printf("  [goal >= 10x]\n");
    }
    close_timed(ours, n_models);
    free(t_tip);
    return rc;
}

int mocapctl_bench_model(const char *which, const mocapctl_bench_options *o)
{
    const int all = strcmp(which, "all") == 0;
    const int do_pipeline = all || strcmp(which, "pipeline") == 0;
    const int do_latency = all || strcmp(which, "pipeline") == 0 || strcmp(which, "latency") == 0;
    const int do_scaling = all || strcmp(which, "scaling") == 0;
    const int do_tip = all || strcmp(which, "tip") == 0;
    if (!do_pipeline && !do_latency && !do_scaling && !do_tip) {
        fprintf(stderr, "mocapctl bench: unknown benchmark '%s' (decode, pipeline, latency, "
                        "scaling, tip, all)\n", which);
        return 2;
    }
    bench_ctx *b = (bench_ctx *)calloc(1, sizeof *b);
    if (!b) return 1;
    b->o = o;
    int rc = 0;
    const char *tmp = getenv("TMPDIR");
    snprintf(b->dir, sizeof b->dir, "%s/mocapctl-bench-%ld", tmp && tmp[0] ? tmp : "/tmp",
#if defined(BENCH_HAVE_PTY)
             (long)getpid()
#else
             (long)mocap_monotonic_ns()
#endif
    );
#if defined(_WIN32)
    _mkdir(b->dir);
#else
    mkdir(b->dir, 0700);
#endif
    mocap_status st = mocap_model_open(o->model_path, NULL, &b->model);
    if (st != MOCAP_OK) {
        fprintf(stderr, "mocapctl bench: loading model %s: %s (%s)\n", o->model_path,
                mocap_last_error(), mocap_status_name(st));
        rc = 1;
        goto done;
    }
    mocap_model_get_info(b->model, &b->info);
    {
        mocap_session_config defaults;
        mocap_config_defaults(&defaults);
        b->sensors = o->sensor_count ? o->sensor_count : defaults.sensor_count;
    }
    printf("bench: model %s (%s, %s), ONNX Runtime %s, %ld CPU cores online, capture: %.0f s "
           "of motion + 8 s prelude (%u sensors at 100 Hz, realistic noise)\n",
           o->model_path, b->info.model_name, b->info.precision, ort_library_version(),
#if defined(_SC_NPROCESSORS_ONLN)
           sysconf(_SC_NPROCESSORS_ONLN),
#else
           -1L,
#endif
           o->seconds, (unsigned)b->sensors);
    st = make_capture(b);
    if (st == MOCAP_OK) st = calibrate_once(b);
    if (st != MOCAP_OK) {
        rc = bench_fail(st, "preparing the capture");
        goto done;
    }
    /* One character first, so the peak RSS is that of one character. */
    if (do_pipeline && bench_pipeline(b) != 0) rc = 1;
    if (do_latency && bench_latency(b) != 0) rc = 1;
    if (do_scaling && bench_scaling(b) != 0) rc = 1;
    if (do_tip) {
        if (!do_pipeline) { /* the end-to-end ratio needs the pipeline figure */
            double fps, wall;
            uint64_t poses;
            if (run_characters(b, 1, &fps, &wall, &poses, NULL) == MOCAP_OK) b->pipeline_fps = fps;
        }
        if (bench_tip(b) != 0) rc = 1;
    }
done:
    mocap_model_close(b->model);
    if (b->capture[0]) remove(b->capture);
    {
        char p[700];
        snprintf(p, sizeof p, "%s/tip_shaped.onnx", b->dir);
        remove(p);
        rmdir(b->dir);
    }
    free(b);
    return rc;
}
