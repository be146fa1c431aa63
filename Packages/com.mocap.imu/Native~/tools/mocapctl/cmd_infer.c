/* mocapctl infer / model-info: the pose model through the engine's ONNX Runtime module.
 *
 *   mocapctl infer --model M.onnx --input IN.tensors --output OUT.tensors
 *                  [--frames T | --stream] [--batch B] [--threads N] [--opt 0-3]
 *                  [--provider cpu|cuda] [--repeat R] [--ort LIBONNXRUNTIME]
 *   mocapctl model-info M.onnx [--ort LIBONNXRUNTIME]
 *
 * Tensor files ("tensor bundle", all little-endian):
 *   8 bytes   magic "MOCAPTNS"
 *   uint32    format version (1)
 *   uint32    number of tensors
 *   per tensor:
 *     char[32]  name, NUL-padded
 *     uint32    rank (1..8)
 *     uint32    dims[rank]
 *     float32   data[product of dims], row-major
 * Input: imu_orientation [B, N, S, 3, 3] and imu_acceleration [B, N, S, 3] with S the model's
 * sensor count (6 for a contract-1 model), optionally imu_mask [B, N, S] (1 present, 0 missing;
 * all ones when absent; only for a model with the mask input, contract 2) and state_in_h /
 * state_in_c [L, B, H] (zeros when absent). Output: joint_rotations
 * [B, N, 24, 3, 3], root_velocity [B, N, 3], foot_contact [B, N, 2] and the state after the last
 * frame, state_out_h / state_out_c [L, B, H].
 *
 * The N frames run in calls of T frames (default: all N in one call; --stream: T = 1, as the
 * engine runs it), the state carried from call to call. --batch B only checks the file's B.
 * Timing of the ort_stream_run calls is printed as one line:
 *   timing: calls C frames_per_call T first_us X p50_us X p99_us X mean_us X
 * (p50/p99/mean over the calls after the first, which includes ONNX Runtime's warm-up; with
 * --repeat R the whole sequence runs R times, state reset each time, the output from the last). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mocap_imu.h"
#include "onnx_runtime.h"
#include "platform.h"
#include "cli_args.h"
#include "commands.h"

#define BUNDLE_MAGIC "MOCAPTNS"
#define BUNDLE_VERSION 1u
#define BUNDLE_MAX_TENSORS 16
#define BUNDLE_NAME 32

typedef struct tensor {
    char name[BUNDLE_NAME + 1];
    uint32_t rank;
    uint32_t dims[8];
    size_t count;
    float *data;
} tensor;

typedef struct bundle {
    int n;
    tensor t[BUNDLE_MAX_TENSORS];
} bundle;

static const char *opt(int argc, char **argv, const char *name) { return cli_value(argc, argv, name); }
static int flag(int argc, char **argv, const char *name) { return cli_flag(argc, argv, name); }

static int report(mocap_status st, const char *what)
{
    fprintf(stderr, "mocapctl: %s: %s (%s)\n", what, mocap_last_error(), mocap_status_name(st));
    return 1;
}

static int host_little_endian(void)
{
    const uint16_t one = 1;
    return *(const uint8_t *)&one == 1;
}

static void bundle_free(bundle *b)
{
    for (int i = 0; i < b->n; ++i) free(b->t[i].data);
    b->n = 0;
}

static int read_u32(FILE *f, uint32_t *v)
{
    uint8_t b[4];
    if (fread(b, 1, 4, f) != 4) return 0;
    *v = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
    return 1;
}

static int write_u32(FILE *f, uint32_t v)
{
    uint8_t b[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    return fwrite(b, 1, 4, f) == 4;
}

static int bundle_read(const char *path, bundle *b)
{
    memset(b, 0, sizeof *b);
    FILE *f = mocap_fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot open %s\n", path);
        return 1;
    }
    char magic[8];
    uint32_t version = 0, count = 0;
    if (fread(magic, 1, 8, f) != 8 || memcmp(magic, BUNDLE_MAGIC, 8) != 0 ||
        !read_u32(f, &version) || !read_u32(f, &count)) {
        fprintf(stderr, "mocapctl: %s is not a tensor bundle (magic %s)\n", path, BUNDLE_MAGIC);
        fclose(f);
        return 1;
    }
    if (version != BUNDLE_VERSION || count > BUNDLE_MAX_TENSORS) {
        fprintf(stderr, "mocapctl: %s: bundle version %u with %u tensors not supported\n", path,
                version, count);
        fclose(f);
        return 1;
    }
    for (uint32_t i = 0; i < count; ++i) {
        tensor *t = &b->t[b->n];
        if (fread(t->name, 1, BUNDLE_NAME, f) != BUNDLE_NAME || !read_u32(f, &t->rank) ||
            t->rank < 1 || t->rank > 8)
            goto truncated;
        t->name[BUNDLE_NAME] = '\0';
        t->count = 1;
        for (uint32_t d = 0; d < t->rank; ++d) {
            if (!read_u32(f, &t->dims[d])) goto truncated;
            t->count *= t->dims[d];
        }
        if (t->count > ((size_t)1 << 31)) goto truncated;
        t->data = (float *)malloc(t->count ? t->count * sizeof(float) : 1);
        if (!t->data || fread(t->data, sizeof(float), t->count, f) != t->count) {
            free(t->data);
            goto truncated;
        }
        if (!host_little_endian()) {
            for (size_t k = 0; k < t->count; ++k) {
                uint8_t *p = (uint8_t *)&t->data[k], x;
                x = p[0]; p[0] = p[3]; p[3] = x;
                x = p[1]; p[1] = p[2]; p[2] = x;
            }
        }
        b->n++;
    }
    fclose(f);
    return 0;
truncated:
    fprintf(stderr, "mocapctl: %s: tensor %d is truncated or malformed\n", path, b->n);
    fclose(f);
    bundle_free(b);
    return 1;
}

static tensor *bundle_find(bundle *b, const char *name)
{
    for (int i = 0; i < b->n; ++i)
        if (strcmp(b->t[i].name, name) == 0) return &b->t[i];
    return NULL;
}

static int bundle_write(const char *path, const bundle *b)
{
    FILE *f = mocap_fopen(path, "wb");
    if (!f) {
        fprintf(stderr, "mocapctl: cannot write %s\n", path);
        return 1;
    }
    int ok = fwrite(BUNDLE_MAGIC, 1, 8, f) == 8 && write_u32(f, BUNDLE_VERSION) &&
             write_u32(f, (uint32_t)b->n);
    for (int i = 0; ok && i < b->n; ++i) {
        const tensor *t = &b->t[i];
        char name[BUNDLE_NAME] = {0};
        strncpy(name, t->name, BUNDLE_NAME - 1);
        ok = fwrite(name, 1, BUNDLE_NAME, f) == BUNDLE_NAME && write_u32(f, t->rank);
        for (uint32_t d = 0; ok && d < t->rank; ++d) ok = write_u32(f, t->dims[d]);
        if (ok && host_little_endian())
            ok = fwrite(t->data, sizeof(float), t->count, f) == t->count;
        else
            for (size_t k = 0; ok && k < t->count; ++k) {
                uint32_t v;
                memcpy(&v, &t->data[k], 4);
                ok = write_u32(f, v);
            }
    }
    if (fclose(f) != 0) ok = 0;
    if (!ok) {
        fprintf(stderr, "mocapctl: writing %s failed\n", path);
        return 1;
    }
    return 0;
}

static int new_tensor(bundle *b, const char *name, uint32_t rank, const uint32_t *dims)
{
    tensor *t = &b->t[b->n];
    memset(t, 0, sizeof *t);
    snprintf(t->name, sizeof t->name, "%s", name);
    t->rank = rank;
    t->count = 1;
    for (uint32_t d = 0; d < rank; ++d) {
        t->dims[d] = dims[d];
        t->count *= dims[d];
    }
    t->data = (float *)calloc(t->count ? t->count : 1, sizeof(float));
    if (!t->data) return -1;
    return b->n++;
}

static int check_shape(const tensor *t, uint32_t rank, const uint32_t *want, const char *shape)
{
    int ok = t->rank == rank;
    for (uint32_t d = 0; ok && d < rank; ++d) ok = want[d] == 0 || t->dims[d] == want[d];
    if (!ok) {
        fprintf(stderr, "mocapctl: input tensor %s has shape [", t->name);
        for (uint32_t d = 0; d < t->rank; ++d) fprintf(stderr, "%s%u", d ? ", " : "", t->dims[d]);
        fprintf(stderr, "], expected %s\n", shape);
    }
    return ok;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static void print_info(const char *path, const ort_model_info *info)
{
    printf("model %s\n", path);
    printf("  onnx runtime      %s (%s)\n", ort_library_version(), ort_library_path());
    printf("  model_name        %s\n", info->model_name);
    printf("  contract_version  %d\n", info->contract_version);
    printf("  precision         %s\n", info->precision);
    printf("  frame_rate        %g\n", info->frame_rate);
    printf("  sensor_order      %s\n", info->sensor_order);
    printf("  sensor_count      %d\n", info->sensor_count);
    printf("  optional          ");
    int optional = 0;
    for (int k = 0; k < info->sensor_count && k < MOCAP_MAX_SENSORS; ++k) {
        if ((info->required_mask >> k) & 1u) continue;
        printf("%s%s", optional++ ? "," : "", mocap_segment_name(info->sensor_segments[k]));
    }
    printf("%s\n", optional ? "" : "none");
    printf("  imu_mask          %s\n", info->has_mask ? "yes" : "no");
    if (info->has_stride_scaling)
        printf("  stride_scaling    training_height %.3f m, exponent %.2f\n", info->training_height,
               info->stride_exponent);
    else
        printf("  stride_scaling    none\n");
    printf("  state             layers %d, size %d\n", info->state_layers, info->state_size);
    printf("  joints            # name parent rest_offset_m\n");
    for (int j = 0; j < ORT_JOINTS; ++j)
        printf("    %2d %-15s %3d  %8.4f %8.4f %8.4f\n", j, info->joint_names[j],
               info->joint_parents[j], info->rest_offsets[j][0], info->rest_offsets[j][1],
               info->rest_offsets[j][2]);
}

int cmd_model_info(int argc, char **argv)
{
    if (argc < 1 || argv[0][0] == '-') return mocapctl_usage_error("model-info");
    ort_options o;
    ort_options_defaults(&o);
    o.library_path = opt(argc, argv, "--ort");
    ort_model *m = NULL;
    mocap_status st = ort_model_open(argv[0], &o, &m);
    if (st != MOCAP_OK) return report(st, "opening model");
    print_info(argv[0], ort_model_get_info(m));
    ort_model_close(m);
    return 0;
}

/* Copy frames [f0, f0 + T) of every character between the whole-sequence arrays ([B][N][k]) and
 * a stream's buffers ([B][T][k]). */
static void gather(float *dst, const float *src, int B, int N, int T, int f0, size_t k)
{
    for (int b = 0; b < B; ++b)
        memcpy(dst + (size_t)b * T * k, src + ((size_t)b * N + f0) * k, (size_t)T * k * sizeof(float));
}
static void scatter(float *dst, const float *src, int B, int N, int T, int f0, size_t k)
{
    for (int b = 0; b < B; ++b)
        memcpy(dst + ((size_t)b * N + f0) * k, src + (size_t)b * T * k, (size_t)T * k * sizeof(float));
}

int cmd_infer(int argc, char **argv)
{
    const char *model_path = opt(argc, argv, "--model");
    const char *in_path = opt(argc, argv, "--input");
    const char *out_path = opt(argc, argv, "--output");
    if (!model_path || !in_path || !out_path) return mocapctl_usage_error("infer");
    /* Numbers first, before anything is read: 0 = not given (the whole clip, any batch). */
    const int frames = (int)cli_integer(argc, argv, "--frames", 0, 1, 1 << 30);
    const int batch = (int)cli_integer(argc, argv, "--batch", 0, 1, 1 << 20);
    const char *provider = opt(argc, argv, "--provider");
    const int repeat = (int)cli_integer(argc, argv, "--repeat", 1, 1, 1000000);

    ort_options o;
    ort_options_defaults(&o);
    o.library_path = opt(argc, argv, "--ort");
    /* ONNX Runtime starts every intra-op thread asked for: 100,000 would never finish. */
    o.intra_op_threads = (int)cli_integer(argc, argv, "--threads", o.intra_op_threads, 1, 256);
    o.optimization_level = (int)cli_integer(argc, argv, "--opt", o.optimization_level, 0, 99);
    if (provider && strcmp(provider, "cuda") == 0) o.provider = ORT_PROVIDER_CUDA;
    else if (provider && strcmp(provider, "cpu") != 0) {
        fprintf(stderr, "mocapctl: --provider must be cpu or cuda\n");
        return 2;
    }

    bundle in, out;
    memset(&out, 0, sizeof out);
    if (bundle_read(in_path, &in) != 0) return 1;
    int rc = 1;
    ort_model *m = NULL;
    ort_stream *main_stream = NULL, *tail_stream = NULL;
    double *times = NULL;

    tensor *ori = bundle_find(&in, "imu_orientation");
    tensor *acc = bundle_find(&in, "imu_acceleration");
    tensor *mask = bundle_find(&in, "imu_mask");
    if (!ori || !acc) {
        fprintf(stderr, "mocapctl: %s lacks imu_orientation or imu_acceleration\n", in_path);
        goto done;
    }
    /* The model says how many sensors the inputs hold. */
    mocap_status st = ort_model_open(model_path, &o, &m);
    if (st != MOCAP_OK) {
        rc = report(st, "opening model");
        goto done;
    }
    const ort_model_info *info = ort_model_get_info(m);
    const uint32_t S = (uint32_t)info->sensor_count;
    char shape[96];
    snprintf(shape, sizeof shape, "[B, N, %u, 3, 3] (the model's %u sensors)", S, S);
    const uint32_t want_ori[5] = {0, 0, S, 3, 3};
    if (!check_shape(ori, 5, want_ori, shape)) goto done;
    const uint32_t want_acc[4] = {ori->dims[0], ori->dims[1], S, 3};
    snprintf(shape, sizeof shape, "[B, N, %u, 3] matching imu_orientation", S);
    if (!check_shape(acc, 4, want_acc, shape)) goto done;
    if (mask && !info->has_mask) {
        fprintf(stderr, "mocapctl: %s holds imu_mask but the model has no mask input (contract %d)\n",
                in_path, info->contract_version);
        goto done;
    }
    const uint32_t want_mask[3] = {ori->dims[0], ori->dims[1], S};
    snprintf(shape, sizeof shape, "[B, N, %u] matching imu_orientation", S);
    if (mask && !check_shape(mask, 3, want_mask, shape)) goto done;
    const int B = (int)ori->dims[0], N = (int)ori->dims[1];
    if (B < 1 || N < 1) {
        fprintf(stderr, "mocapctl: %s holds no frames\n", in_path);
        goto done;
    }
    if (batch && batch != B) {
        fprintf(stderr, "mocapctl: --batch %d but %s holds %d characters\n", batch, in_path, B);
        goto done;
    }
    int T = N;
    if (flag(argc, argv, "--stream")) T = 1;
    else if (frames) T = frames;
    if (T > N) T = N;

    const int L = info->state_layers, H = info->state_size;
    const uint32_t want_state[3] = {(uint32_t)L, (uint32_t)B, (uint32_t)H};
    tensor *h0 = bundle_find(&in, "state_in_h"), *c0 = bundle_find(&in, "state_in_c");
    if ((h0 && !check_shape(h0, 3, want_state, "[L, B, H] of the model")) ||
        (c0 && !check_shape(c0, 3, want_state, "[L, B, H] of the model")))
        goto done;

    st = ort_stream_create(m, B, T, &main_stream);
    if (st == MOCAP_OK && N % T) st = ort_stream_create(m, B, N % T, &tail_stream);
    if (st != MOCAP_OK) {
        rc = report(st, "binding tensors");
        goto done;
    }
    const uint32_t d_rot[5] = {(uint32_t)B, (uint32_t)N, 24, 3, 3};
    const uint32_t d_vel[3] = {(uint32_t)B, (uint32_t)N, 3}, d_con[3] = {(uint32_t)B, (uint32_t)N, 2};
    int i_rot = new_tensor(&out, "joint_rotations", 5, d_rot);
    int i_vel = new_tensor(&out, "root_velocity", 3, d_vel);
    int i_con = new_tensor(&out, "foot_contact", 3, d_con);
    int i_h = new_tensor(&out, "state_out_h", 3, want_state);
    int i_c = new_tensor(&out, "state_out_c", 3, want_state);
    const int calls_per_pass = (N + T - 1) / T;
    times = (double *)malloc((size_t)calls_per_pass * (size_t)repeat * sizeof(double));
    if (i_rot < 0 || i_vel < 0 || i_con < 0 || i_h < 0 || i_c < 0 || !times) {
        fprintf(stderr, "mocapctl: out of memory\n");
        goto done;
    }
    const size_t state_bytes = ort_stream_state_count(main_stream) * sizeof(float);
    int calls = 0;
    for (int pass = 0; pass < repeat; ++pass) {
        ort_stream *s = main_stream;
        if (h0) memcpy(ort_stream_state_h(s), h0->data, state_bytes);
        else memset(ort_stream_state_h(s), 0, state_bytes);
        if (c0) memcpy(ort_stream_state_c(s), c0->data, state_bytes);
        else memset(ort_stream_state_c(s), 0, state_bytes);
        for (int f0 = 0; f0 < N; f0 += T) {
            int t = N - f0 < T ? N - f0 : T;
            if (t != T) { /* the last, shorter call continues the state in the tail stream */
                memcpy(ort_stream_state_h(tail_stream), ort_stream_state_h(s), state_bytes);
                memcpy(ort_stream_state_c(tail_stream), ort_stream_state_c(s), state_bytes);
                s = tail_stream;
            }
            gather(ort_stream_orientation(s), ori->data, B, N, t, f0, (size_t)S * 9);
            gather(ort_stream_acceleration(s), acc->data, B, N, t, f0, (size_t)S * 3);
            float *mask_in = ort_stream_mask(s);
            if (mask_in && mask) {
                gather(mask_in, mask->data, B, N, t, f0, S);
            } else if (mask_in) {
                for (size_t k = 0; k < (size_t)B * (size_t)t * S; ++k) mask_in[k] = 1.0f;
            }
            int64_t t0 = mocap_monotonic_ns();
            st = ort_stream_run(s);
            times[calls++] = (double)(mocap_monotonic_ns() - t0) * 1e-3;
            if (st != MOCAP_OK) {
                rc = report(st, "running the model");
                goto done;
            }
            scatter(out.t[i_rot].data, ort_stream_joint_rotations(s), B, N, t, f0, 216);
            scatter(out.t[i_vel].data, ort_stream_root_velocity(s), B, N, t, f0, 3);
            scatter(out.t[i_con].data, ort_stream_foot_contact(s), B, N, t, f0, 2);
        }
        memcpy(out.t[i_h].data, ort_stream_state_h(s), state_bytes);
        memcpy(out.t[i_c].data, ort_stream_state_c(s), state_bytes);
    }
    if (bundle_write(out_path, &out) != 0) goto done;

    double first = times[0];
    int n_rest = calls - 1;
    double p50 = first, p99 = first, mean = first;
    if (n_rest > 0) {
        qsort(times + 1, (size_t)n_rest, sizeof(double), cmp_double);
        p50 = times[1 + (int)floor(0.50 * (n_rest - 1) + 0.5)];
        p99 = times[1 + (int)floor(0.99 * (n_rest - 1) + 0.5)];
        double sum = 0;
        for (int i = 1; i < calls; ++i) sum += times[i];
        mean = sum / n_rest;
    }
    char threads_text[32];
    if (o.intra_op_threads > 0)
        snprintf(threads_text, sizeof threads_text, "%d intra-op thread%s", o.intra_op_threads,
                 o.intra_op_threads == 1 ? "" : "s");
    else
        snprintf(threads_text, sizeof threads_text, "default intra-op threads");
    printf("infer: %s (%s, %s) on ONNX Runtime %s, %d character%s x %d frames in calls of %d, "
           "%s, %d pass%s -> %s\n",
           model_path, info->model_name, info->precision, ort_library_version(), B, B == 1 ? "" : "s",
           N, T, threads_text, repeat, repeat == 1 ? "" : "es", out_path);
    printf("timing: calls %d frames_per_call %d first_us %.1f p50_us %.1f p99_us %.1f mean_us %.1f\n",
           calls, T, first, p50, p99, mean);
    rc = 0;
done:
    free(times);
    ort_stream_destroy(main_stream);
    ort_stream_destroy(tail_stream);
    ort_model_close(m);
    bundle_free(&in);
    bundle_free(&out);
    return rc;
}
