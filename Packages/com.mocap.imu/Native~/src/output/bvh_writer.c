/* Streaming BVH writer: see bvh_writer.h. */
#if !defined(_WIN32)
#define _FILE_OFFSET_BITS 64 /* long recordings pass 2 GiB */
#define _POSIX_C_SOURCE 200809L /* ftello, fseeko */
#endif
#include "bvh_writer.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "platform.h"
#include "mocap_math.h"
#include "text_number.h"

#define PI 3.14159265358979323846
#define COUNT_WIDTH 12 /* digits reserved for "Frames: N" so it can be rewritten in place */
#define MIN_END_SITE_M 0.05

struct bvh_writer {
    FILE *file;
    char path[MOCAP_PATH_MAX];
    bvh_skeleton skeleton;
    bvh_rotation_order order;
    int32_t file_order[BVH_MAX_JOINTS]; /* depth-first joint order = MOTION column order */
    int64_t count_offset;               /* file offset of the frame count digits */
    uint64_t frames;                    /* complete frame lines written */
    uint64_t frames_counted;            /* value in the header now */
    uint32_t flush_every;
    uint32_t since_flush;
    int have_previous;
    double previous[BVH_MAX_JOINTS][3]; /* last written Euler angles (radians), for continuity */
    mocap_status error;                 /* first write error */
    char error_text[256];               /* its message, repeated by every later call */
};

/* ------------------------------------------------------------------------------------------ */
/* Euler angles                                                                                */

/* Axis indices of the three rotations of each order. */
static void order_axes(bvh_rotation_order order, int axes[3])
{
    if (order == BVH_ORDER_XYZ) {
        axes[0] = 0, axes[1] = 1, axes[2] = 2;
    } else {
        axes[0] = 2, axes[1] = 0, axes[2] = 1;
    }
}

static double wrap_near(double angle, double target)
{
    return angle + 2.0 * PI * floor((target - angle) / (2.0 * PI) + 0.5);
}

/* Rotation about axis i by a (row-major), the convention of training/bvh.py. */
static void axis_rotation(int i, double a, double m[9])
{
    if (i == 0) mat3_rotation_x(m, a);
    else if (i == 1) mat3_rotation_y(m, a);
    else mat3_rotation_z(m, a);
}

void bvh_euler_from_matrix(const double m[9], bvh_rotation_order order, const double *previous,
                           double angles[3])
{
    int ax[3];
    order_axes(order, ax);
    const int i = ax[0], j = ax[1], k = ax[2];
    /* +1 when (i, j, k) is a cyclic permutation of (0, 1, 2). */
    const double s = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
#define M(r, c) m[(r) * 3 + (c)]
    double sb = s * M(i, k);
    if (sb > 1.0) sb = 1.0;
    if (sb < -1.0) sb = -1.0;
    double a, b = asin(sb), c;
    const double cb = sqrt(M(i, i) * M(i, i) + M(i, j) * M(i, j));
    if (cb > 1e-7) {
        a = atan2(-s * M(j, k), M(k, k));
        c = atan2(-s * M(i, j), M(i, i));
    } else {
        /* Gimbal lock: only a + c (or a - c) is defined; put it all in the first angle. */
        c = 0.0;
        double rj[9], rjt[9], ri[9];
        axis_rotation(j, b, rj);
        mat3_transpose(rjt, rj);
        mat3_multiply(ri, m, rjt); /* = R_i(a) */
        const int j2 = (i + 1) % 3, k2 = (i + 2) % 3;
        a = atan2(ri[k2 * 3 + j2], ri[j2 * 3 + j2]);
    }
#undef M
    if (!previous) {
        angles[0] = a, angles[1] = b, angles[2] = c;
        return;
    }
    /* The other solution (a + pi, pi - b, c + pi) describes the same rotation; of both, with
     * 2*pi shifts, take the one nearest the previous frame. */
    double cand[2][3] = {{a, b, c}, {a + PI, PI - b, c + PI}};
    double best = INFINITY;
    for (int n = 0; n < 2; ++n) {
        double d = 0;
        for (int q = 0; q < 3; ++q) {
            cand[n][q] = wrap_near(cand[n][q], previous[q]);
            d += fabs(cand[n][q] - previous[q]);
        }
        if (d < best) {
            best = d;
            memcpy(angles, cand[n], sizeof cand[n]);
        }
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Skeleton                                                                                    */

mocap_status bvh_skeleton_from_model_info(const mocap_model_info *info, bvh_skeleton *out)
{
    if (!info || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: NULL argument");
    memset(out, 0, sizeof *out);
    out->joint_count = MOCAP_JOINT_COUNT;
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        snprintf(out->names[j], BVH_NAME_CAP, "%.*s", BVH_NAME_CAP - 1, info->joint_names[j]);
        out->parents[j] = info->joint_parents[j];
        for (int k = 0; k < 3; ++k) out->offsets[j][k] = info->rest_offsets[j][k];
    }
    /* Metadata joint 0 holds the pelvis height above the floor: the root rest position. */
    return MOCAP_OK;
}

static int valid_name(const char *n)
{
    if (!n[0]) return 0;
    for (const char *p = n; *p; ++p)
        if (*p <= ' ' || *p == '{' || *p == '}' || (unsigned char)*p >= 127) return 0;
    return 1;
}

static mocap_status check_skeleton(const bvh_skeleton *sk)
{
    if (sk->joint_count < 1 || sk->joint_count > BVH_MAX_JOINTS)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: %d joints (1..%d)", sk->joint_count,
                          BVH_MAX_JOINTS);
    if (sk->parents[0] != -1)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: joint 0 must be the root (parent -1)");
    for (int j = 0; j < sk->joint_count; ++j) {
        if (memchr(sk->names[j], 0, BVH_NAME_CAP) == NULL || !valid_name(sk->names[j]))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "bvh: joint %d has no usable name (non-empty, no spaces or braces)", j);
        if (j > 0 && (sk->parents[j] < 0 || sk->parents[j] >= j))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "bvh: joint %d (%s) has parent %d; parents must come first", j,
                              sk->names[j], sk->parents[j]);
        for (int k = 0; k < 3; ++k)
            if (!isfinite(sk->offsets[j][k]))
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: joint %d offset not finite", j);
    }
    return MOCAP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Writing                                                                                     */

static mocap_status io_error(bvh_writer *w, const char *what)
{
    char buf[128];
    mocap_status st = mocap_fail(MOCAP_ERR_IO, "bvh: %s %s: %s", what, w->path,
                                 mocap_errno_text(errno, buf, sizeof buf));
    if (w->error == MOCAP_OK) {
        w->error = st;
        mocap_copy_error(w->error_text, sizeof w->error_text);
    }
    return st;
}

/* A writer that failed stays failed: every later call returns the first error with its text
 * (mocap_last_error would otherwise still hold whatever the thread did in between). */
static mocap_status earlier_error(const bvh_writer *w)
{
    return mocap_fail(w->error, "%s (nothing written since)", w->error_text);
}

static void indent(FILE *f, int depth)
{
    for (int d = 0; d < depth; ++d) fputc('\t', f);
}

/* Writes joint j and its subtree; appends to file_order. */
/* "OFFSET x y z" with '.' in any locale. */
static void write_offset(FILE *f, double x, double y, double z)
{
    char line[128];
    snprintf(line, sizeof line, "OFFSET %.6f %.6f %.6f\n", x, y, z);
    text_use_dot(line, text_locale_point());
    fputs(line, f);
}

static void write_joint(bvh_writer *w, int j, int depth, int *n)
{
    FILE *f = w->file;
    const bvh_skeleton *sk = &w->skeleton;
    static const char *rot_names[2] = {"Zrotation Xrotation Yrotation",
                                       "Xrotation Yrotation Zrotation"};
    w->file_order[(*n)++] = j;
    indent(f, depth);
    fprintf(f, "%s %s\n", j == 0 ? "ROOT" : "JOINT", sk->names[j]);
    indent(f, depth);
    fputs("{\n", f);
    indent(f, depth + 1);
    write_offset(f, sk->offsets[j][0], sk->offsets[j][1], sk->offsets[j][2]);
    indent(f, depth + 1);
    if (j == 0)
        fprintf(f, "CHANNELS 6 Xposition Yposition Zposition %s\n", rot_names[w->order]);
    else
        fprintf(f, "CHANNELS 3 %s\n", rot_names[w->order]);
    int children = 0;
    for (int c = j + 1; c < sk->joint_count; ++c) {
        if (sk->parents[c] != j) continue;
        children++;
        write_joint(w, c, depth + 1, n);
    }
    if (!children) {
        /* End Site: continue the joint's own bone by half its length (5 cm at least). */
        double d[3] = {sk->offsets[j][0], sk->offsets[j][1], sk->offsets[j][2]};
        double len = vec3_norm(d);
        double e[3] = {0.0, MIN_END_SITE_M, 0.0};
        if (j > 0 && len > 1e-6) {
            double l = 0.5 * len < MIN_END_SITE_M ? MIN_END_SITE_M : 0.5 * len;
            for (int k = 0; k < 3; ++k) e[k] = d[k] / len * l;
        }
        indent(f, depth + 1);
        fputs("End Site\n", f);
        indent(f, depth + 1);
        fputs("{\n", f);
        indent(f, depth + 2);
        write_offset(f, e[0], e[1], e[2]);
        indent(f, depth + 1);
        fputs("}\n", f);
    }
    indent(f, depth);
    fputs("}\n", f);
}

/* 64-bit file offsets: long is 32 bits on Windows, and a long session's BVH passes 2 GiB. */
static int64_t file_tell(FILE *f)
{
#if defined(_WIN32)
    return _ftelli64(f);
#else
    return (int64_t)ftello(f);
#endif
}

static int file_seek(FILE *f, int64_t offset)
{
#if defined(_WIN32)
    return _fseeki64(f, offset, SEEK_SET);
#else
    return fseeko(f, (off_t)offset, SEEK_SET);
#endif
}

static mocap_status write_count(bvh_writer *w)
{
    if (w->frames == w->frames_counted) return MOCAP_OK;
    int64_t end = file_tell(w->file);
    if (end < 0 || file_seek(w->file, w->count_offset) != 0) return io_error(w, "seeking in");
    fprintf(w->file, "%-*llu", COUNT_WIDTH, (unsigned long long)w->frames);
    if (file_seek(w->file, end) != 0) return io_error(w, "seeking in");
    w->frames_counted = w->frames;
    return MOCAP_OK;
}

mocap_status bvh_writer_open(const char *path, const bvh_skeleton *skeleton, double frame_time_s,
                             bvh_rotation_order order, bvh_writer **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: out is NULL");
    *out = NULL;
    if (!path || !path[0] || !skeleton)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: path and skeleton are required");
    if (!(frame_time_s > 0.0) || frame_time_s > 10.0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: frame time %g s out of range",
                          frame_time_s);
    if (order != BVH_ORDER_ZXY && order != BVH_ORDER_XYZ)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: unknown rotation order %d", (int)order);
    mocap_status st = check_skeleton(skeleton);
    if (st != MOCAP_OK) return st;
    if (strlen(path) >= MOCAP_PATH_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: path too long: %s", path);

    bvh_writer *w = (bvh_writer *)calloc(1, sizeof *w);
    if (!w) return mocap_fail(MOCAP_ERR_NO_MEMORY, "bvh: out of memory");
    snprintf(w->path, sizeof w->path, "%s", path);
    w->skeleton = *skeleton;
    w->order = order;
    w->flush_every = 1;
    w->file = mocap_fopen(path, "wb");
    if (!w->file) {
        char buf[128];
        st = mocap_fail(errno == ENOENT ? MOCAP_ERR_NOT_FOUND : MOCAP_ERR_IO,
                        "bvh: cannot create %s: %s", path, mocap_errno_text(errno, buf, sizeof buf));
        free(w);
        return st;
    }
    fputs("HIERARCHY\n", w->file);
    int n = 0;
    write_joint(w, 0, 0, &n);
    fputs("MOTION\nFrames: ", w->file);
    w->count_offset = file_tell(w->file);
    fprintf(w->file, "%-*u\n", COUNT_WIDTH, 0u);
    char frame_time[64];
    text_format_double(frame_time, sizeof frame_time, "Frame Time: %.8f\n", frame_time_s);
    fputs(frame_time, w->file);
    if (n != skeleton->joint_count || ferror(w->file) || fflush(w->file) != 0 || w->count_offset < 0) {
        st = n != skeleton->joint_count
                 ? mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: skeleton is not one tree")
                 : io_error(w, "writing");
        fclose(w->file);
        mocap_remove_file(path);
        free(w);
        return st;
    }
    *out = w;
    return MOCAP_OK;
}

void bvh_writer_set_flush_every(bvh_writer *w, uint32_t frames)
{
    if (w) w->flush_every = frames ? frames : 1;
}

uint64_t bvh_writer_frames(const bvh_writer *w) { return w ? w->frames : 0; }

mocap_status bvh_writer_flush(bvh_writer *w)
{
    if (!w) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: writer is NULL");
    if (w->error != MOCAP_OK) return earlier_error(w);
    if (fflush(w->file) != 0) return io_error(w, "writing");
    mocap_status st = write_count(w);
    if (st != MOCAP_OK) return st;
    if (fflush(w->file) != 0 || ferror(w->file)) return io_error(w, "writing");
    w->since_flush = 0;
    return MOCAP_OK;
}

/* "%.*f" without a "-0" and without trailing zeros (smaller files, same values). */
static void put_number(FILE *f, double v, int decimals, int first, char locale_point)
{
    char buf[64];
    int len = snprintf(buf, sizeof buf, "%.*f", decimals, v);
    if (len <= 0 || len >= (int)sizeof buf) {
        fputs(first ? "0" : " 0", f);
        return;
    }
    text_use_dot(buf, locale_point); /* BVH wants '.', whatever the host's locale */
    char *dot = strchr(buf, '.');
    if (dot) {
        char *e = buf + len - 1;
        while (e > dot && *e == '0') *e-- = 0;
        if (e == dot) *e = 0;
    }
    const char *s = (strcmp(buf, "-0") == 0) ? "0" : buf;
    if (!first) fputc(' ', f);
    fputs(s, f);
}

mocap_status bvh_writer_append(bvh_writer *w, const float root_position[3],
                               const float (*rotations)[4])
{
    if (!w || !root_position || !rotations)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: NULL argument");
    if (w->error != MOCAP_OK) return earlier_error(w);
    const int J = w->skeleton.joint_count;
    double angles[BVH_MAX_JOINTS][3];
    for (int j = 0; j < J; ++j) {
        double q[4] = {rotations[j][0], rotations[j][1], rotations[j][2], rotations[j][3]};
        int finite = isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2]) && isfinite(q[3]);
        if (!finite || quat_normalize(q) != 0) quat_identity(q);
        double m[9];
        quat_to_mat3(m, q);
        bvh_euler_from_matrix(m, w->order, w->have_previous ? w->previous[j] : NULL, angles[j]);
        memcpy(w->previous[j], angles[j], sizeof angles[j]);
    }
    w->have_previous = 1;
    FILE *f = w->file;
    const char point = text_locale_point();
    for (int n = 0; n < J; ++n) {
        const int j = w->file_order[n];
        if (j == 0) {
            for (int k = 0; k < 3; ++k) {
                double p = isfinite(root_position[k]) ? root_position[k] : 0.0;
                put_number(f, p, 6, n == 0 && k == 0, point);
            }
        }
        for (int k = 0; k < 3; ++k) put_number(f, angles[j][k] * (180.0 / PI), 4, 0, point);
    }
    fputc('\n', f);
    if (ferror(f)) return io_error(w, "writing");
    w->frames++;
    if (++w->since_flush >= w->flush_every) return bvh_writer_flush(w);
    return MOCAP_OK;
}

mocap_status bvh_writer_append_pose(bvh_writer *w, const mocap_pose *pose)
{
    if (!w || !pose) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: NULL argument");
    if (w->skeleton.joint_count != MOCAP_JOINT_COUNT)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "bvh: a pose has %d joints, the skeleton %d",
                          MOCAP_JOINT_COUNT, w->skeleton.joint_count);
    return bvh_writer_append(w, pose->root_position,
                             (const float(*)[4])pose->joint_rotations);
}

mocap_status bvh_writer_close(bvh_writer *w)
{
    if (!w) return MOCAP_OK;
    mocap_status st = w->error != MOCAP_OK ? earlier_error(w) : bvh_writer_flush(w);
    if (fclose(w->file) != 0 && st == MOCAP_OK) st = io_error(w, "closing");
    free(w);
    return st;
}
