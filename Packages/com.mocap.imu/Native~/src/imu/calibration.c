/* Calibration: collecting still windows, turning them into per-sensor world alignment, mounting
 * rotation and acceleration offset, applying the result to every frame, and the file format.
 * The formulas are stated at the top of calibration.h and derived in docs/calibration.md. */
#include "calibration.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "platform.h"
#include "mocap_math.h"
#include "segments.h"
#include "text_number.h"

/* Mask of the first n sensors (n <= MOCAP_MAX_SENSORS < 32). */
static uint32_t first_sensors(uint32_t n) { return (1u << n) - 1u; }
#define KEPT_MAX 1024u
/* A forward axis whose horizontal part is below this (it points within 30 deg of vertical) gives
 * no usable heading; the bone's side axis, then nearly horizontal, is used instead. */
#define HEADING_RESET_MIN_HORIZONTAL 0.5
/* Stored matrices are floats (~1e-7 relative); anything further from a rotation than this was
 * edited or corrupted. */
#define ORTHONORMAL_TOLERANCE 1e-5
#define CALIB_FILE_HEADER "mocap-calibration"
/* Version 2 lists its sensors by segment name; version 1 (before sensor sets) always held the
 * six sensors below, in this order, and is still read. */
#define CALIB_FILE_VERSION 2
static const char *const VERSION1_SENSORS[] = {"pelvis", "left_wrist", "right_wrist",
                                               "left_shin", "right_shin", "head"};

static const char *step_name(int32_t step)
{
    switch (step) {
    case MOCAP_CALIBRATION_HEADING: return "heading";
    case MOCAP_CALIBRATION_TPOSE: return "T-pose";
    case MOCAP_CALIBRATION_HEADING_RESET: return "heading reset";
    default: return "unknown step";
    }
}

/* ---- small conversions between the float storage and double maths ---- */

static void load_mat(double out[9], const float in[9])
{
    for (int i = 0; i < 9; i++)
        out[i] = (double)in[i];
}

static void store_mat(float out[9], const double in[9])
{
    for (int i = 0; i < 9; i++)
        out[i] = (float)in[i];
}

/* The world-to-model mapping used for a sensor without a heading step: the world frame's
 * conventional forward (north) becomes model forward. NWU has north on X, ENU on Y. */
static void conventional_world_to_model(int32_t world_frame, double w[9])
{
    double a[9], rz[9];
    mocap_world_zup_to_model(a);
    mat3_rotation_z(rz, world_frame == MOCAP_WORLD_ENU ? -0.5 * MOCAP_PI : 0.0);
    mat3_multiply(w, a, rz);
}

/* ---- collection ---- */

void calib_init(calib_accumulator *acc, uint32_t sensor_count, const int32_t *segments,
                uint32_t optional_mask)
{
    memset(acc, 0, sizeof *acc);
    acc->sensor_count = sensor_count;
    memcpy(acc->segments, segments, sensor_count * sizeof *segments);
    acc->optional_mask = optional_mask & first_sensors(sensor_count);
    acc->step = -1;
    acc->state = MOCAP_CALIBRATION_IDLE;
    acc->start_t = -1.0;
}

void calib_begin(calib_accumulator *acc, int32_t step, double start_t, double duration)
{
    /* Only the counters and sums need clearing: kept_quat entries are written before read. */
    acc->step = step;
    acc->state = MOCAP_CALIBRATION_WAITING;
    acc->start_t = (start_t >= 0.0 && isfinite(start_t)) ? start_t : -1.0;
    acc->duration = (duration > 0.0 && isfinite(duration)) ? duration : 0.0;
    acc->frames = 0;
    memset(acc->samples, 0, sizeof acc->samples);
    memset(acc->quat_sum, 0, sizeof acc->quat_sum);
    memset(acc->quat_first, 0, sizeof acc->quat_first);
    memset(acc->force_sum, 0, sizeof acc->force_sum);
    memset(acc->gyro_sq_sum, 0, sizeof acc->gyro_sq_sum);
    memset(acc->kept, 0, sizeof acc->kept);
}

/* Keep at most KEPT_MAX orientations per sensor for the spread, evenly over the window whatever
 * its length: every stride-th sample, halving the kept set and doubling the stride when full.
 * The stride follows from the sample count, so no extra state is needed. */
static void keep_orientation(calib_accumulator *acc, int s, const double q[4])
{
    uint32_t index = acc->samples[s];
    uint32_t stride = 1;
    while ((index + stride - 1) / stride > KEPT_MAX)
        stride *= 2;
    if (index % stride != 0)
        return;
    if (acc->kept[s] == KEPT_MAX) {
        for (uint32_t i = 0; i < KEPT_MAX / 2; i++)
            memcpy(acc->kept_quat[s][i], acc->kept_quat[s][2 * i], sizeof acc->kept_quat[s][i]);
        acc->kept[s] = KEPT_MAX / 2;
        stride *= 2;
        if (index % stride != 0)
            return;
    }
    for (int i = 0; i < 4; i++)
        acc->kept_quat[s][acc->kept[s]][i] = (float)q[i];
    acc->kept[s]++;
}

int calib_add_frame(calib_accumulator *acc, const raw_frame *frame)
{
    if (acc->step < 0 || (acc->state != MOCAP_CALIBRATION_WAITING &&
                          acc->state != MOCAP_CALIBRATION_COLLECTING))
        return 0;
    if (acc->start_t < 0.0)
        acc->start_t = frame->t;
    if (frame->t < acc->start_t)
        return 0;
    /* Frame times are multiples of the output period plus rounding: a frame within a
     * microsecond of the end belongs to the window and closes it. */
    const double end = acc->start_t + acc->duration;
    const double eps = 1e-6;
    if (frame->t > end + eps)
        return 1; /* window already over (scheduled in the past, or a gap in the frames) */
    acc->state = MOCAP_CALIBRATION_COLLECTING;
    acc->frames++;
    for (int s = 0; s < (int)acc->sensor_count; s++) {
        if (!(frame->fresh_mask & (1u << s)))
            continue;
        double q[4];
        quat_copy(q, frame->quat[s]);
        if (acc->samples[s] == 0)
            quat_copy(acc->quat_first[s], q);
        /* Summing needs every sample on one hemisphere. */
        quat_align_hemisphere(q, acc->quat_first[s]);
        for (int i = 0; i < 4; i++)
            acc->quat_sum[s][i] += q[i];
        for (int i = 0; i < 3; i++)
            acc->force_sum[s][i] += frame->force_world[s][i];
        acc->gyro_sq_sum[s] += vec3_dot(frame->gyr[s], frame->gyr[s]);
        keep_orientation(acc, s, q);
        acc->samples[s]++;
    }
    return frame->t >= end - eps ? 1 : 0;
}

/* Window statistics of one sensor. */
typedef struct sensor_stats {
    uint32_t n;
    double mean_quat[4];
    double mean_force[3];
    double gyro_rms_dps;
    double spread_deg;
    double accel_norm_error;
    double tilt_deg;
} sensor_stats;

static void compute_stats(const calib_accumulator *acc, int s, int with_spread, sensor_stats *st)
{
    memset(st, 0, sizeof *st);
    st->n = acc->samples[s];
    quat_identity(st->mean_quat);
    if (st->n == 0)
        return;
    /* The normalised sum of sign-aligned quaternions is the chordal mean: for the few degrees of
     * spread a still window has it equals the true rotation mean to well below 0.01 deg. */
    quat_copy(st->mean_quat, acc->quat_sum[s]);
    if (quat_normalize(st->mean_quat) != 0)
        quat_copy(st->mean_quat, acc->quat_first[s]);
    for (int i = 0; i < 3; i++)
        st->mean_force[i] = acc->force_sum[s][i] / st->n;
    st->gyro_rms_dps = sqrt(acc->gyro_sq_sum[s] / st->n) * MOCAP_RAD2DEG;
    st->accel_norm_error = fabs(vec3_norm(st->mean_force) - MOCAP_STANDARD_GRAVITY);
    double r[9];
    quat_to_mat3(r, st->mean_quat);
    double cz = r[8] > 1.0 ? 1.0 : (r[8] < -1.0 ? -1.0 : r[8]);
    st->tilt_deg = acos(cz) * MOCAP_RAD2DEG;
    if (with_spread && acc->kept[s] > 0) {
        double sq = 0.0;
        for (uint32_t i = 0; i < acc->kept[s]; i++) {
            double q[4];
            for (int k = 0; k < 4; k++)
                q[k] = acc->kept_quat[s][i][k];
            double a = quat_angle_deg(st->mean_quat, q);
            sq += a * a;
        }
        st->spread_deg = sqrt(sq / acc->kept[s]);
    }
}

/* Appends to a fixed buffer, truncating with "..." rather than overflowing. */
typedef struct text_buf {
    char *buf;
    size_t cap;
    size_t len;
} text_buf;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void text_append(text_buf *t, const char *fmt, ...)
{
    if (t->len + 1 >= t->cap)
        return;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(t->buf + t->len, t->cap - t->len, fmt, ap);
    va_end(ap);
    if (n < 0)
        return;
    if ((size_t)n >= t->cap - t->len) {
        t->len = t->cap - 1;
        if (t->cap > 4)
            memcpy(t->buf + t->cap - 4, "...", 4);
    } else {
        t->len += (size_t)n;
    }
}

mocap_status calib_finish(calib_accumulator *acc, mocap_calibration *cal,
                          mocap_calibration_report *report)
{
    const int32_t step = acc->step;
    memset(report, 0, sizeof *report);
    report->step = step;
    report->sensor_count = acc->sensor_count;
    report->progress = 1.0f;
    report->seconds_remaining = 0.0f;
    acc->step = -1; /* the window is consumed whatever the outcome */

    text_buf reason = {report->reason, sizeof report->reason, 0};
    text_append(&reason, "%s refused:", step_name(step));
    int failed = 0;

    if (step < MOCAP_CALIBRATION_HEADING || step > MOCAP_CALIBRATION_HEADING_RESET) {
        text_append(&reason, " calibration step %d is unknown", (int)step);
        failed = 1;
    }

    const uint32_t all = first_sensors(acc->sensor_count);
    uint32_t required = all;
    if (step == MOCAP_CALIBRATION_HEADING_RESET) {
        required = cal->valid_mask & all;
        if (required == 0 && !failed) {
            text_append(&reason, " no sensor is calibrated yet (run heading and T-pose first)");
            failed = 1;
        }
    }
    if (acc->frames == 0 && !failed) {
        text_append(&reason, " no frames arrived in the %.1f s window", acc->duration);
        failed = 1;
    }

    sensor_stats stats[MOCAP_MAX_SENSORS];
    const double min_samples = CALIB_MIN_SAMPLE_FRACTION * acc->frames;
    uint32_t left_out = 0; /* optional sensors that sent nothing: not calibrated, not refused */
    for (int s = 0; s < (int)acc->sensor_count; s++) {
        sensor_stats *st = &stats[s];
        compute_stats(acc, s, 1, st);
        mocap_sensor_quality *q = &report->sensors[s];
        q->gyro_rms_dps = (float)st->gyro_rms_dps;
        q->orientation_spread_deg = (float)st->spread_deg;
        q->accel_norm_error = (float)st->accel_norm_error;
        q->tilt_deg = (float)st->tilt_deg;
        q->samples = st->n;
        q->segment = acc->segments[s];
        q->ok = 1;
        if (!(required & (1u << s)) || acc->frames == 0)
            continue;
        if (st->n == 0 && (acc->optional_mask & (1u << s))) {
            q->ok = 0;
            q->left_out = 1;
            left_out |= 1u << s;
            continue;
        }

        const char *name = segments_name_or(acc->segments[s], "unknown segment");
        int bad = 0;
        if (st->n == 0) {
            text_append(&reason, " %s: no samples;", name);
            bad = 1;
        } else if (st->n < min_samples) {
            text_append(&reason, " %s: %u samples in %u frames < %.0f%%;", name, (unsigned)st->n,
                        (unsigned)acc->frames, CALIB_MIN_SAMPLE_FRACTION * 100.0);
            bad = 1;
        }
        if (st->n > 0) {
            if (step == MOCAP_CALIBRATION_TPOSE && !(cal->heading_mask & (1u << s))) {
                text_append(&reason, " %s: no heading step yet;", name);
                bad = 1;
            }
            if (st->gyro_rms_dps > CALIB_MAX_GYRO_RMS_DPS) {
                text_append(&reason, " %s: gyro %.1f deg/s > %.0f;", name, st->gyro_rms_dps,
                            CALIB_MAX_GYRO_RMS_DPS);
                bad = 1;
            }
            if (st->spread_deg > CALIB_MAX_ORIENTATION_SPREAD_DEG) {
                text_append(&reason, " %s: orientation spread %.1f deg > %.0f;", name,
                            st->spread_deg, CALIB_MAX_ORIENTATION_SPREAD_DEG);
                bad = 1;
            }
            /* A heading reset only needs stillness: the pose may load the sensors unevenly. */
            if (step != MOCAP_CALIBRATION_HEADING_RESET &&
                st->accel_norm_error > CALIB_MAX_ACCEL_NORM_ERROR) {
                text_append(&reason, " %s: |force| %.2f m/s^2, %.2f from g > %.1f;", name,
                            vec3_norm(st->mean_force), st->accel_norm_error,
                            CALIB_MAX_ACCEL_NORM_ERROR);
                bad = 1;
            }
            if (step == MOCAP_CALIBRATION_HEADING && st->tilt_deg > CALIB_MAX_HEADING_TILT_DEG) {
                text_append(&reason, " %s: tilt %.1f deg > %.0f;", name, st->tilt_deg,
                            CALIB_MAX_HEADING_TILT_DEG);
                bad = 1;
            }
        }
        if (bad) {
            q->ok = 0;
            failed = 1;
        }
    }

    required &= ~left_out;
    if (!failed && acc->frames > 0 && required == 0) {
        text_append(&reason, " no sensor sent samples (every configured sensor is optional)");
        failed = 1;
    }
    if (failed) {
        /* Drop the trailing separator for a tidy message. */
        if (reason.len > 0 && report->reason[reason.len - 1] == ';')
            report->reason[--reason.len] = '\0';
        report->state = MOCAP_CALIBRATION_REFUSED;
        acc->state = MOCAP_CALIBRATION_REFUSED;
        return mocap_fail(MOCAP_ERR_BAD_CALIBRATION, "%s", report->reason);
    }

    /* Everything checked: compute into a copy, then publish, so cal is never half-updated. */
    mocap_calibration next = *cal;
    for (int s = 0; s < (int)acc->sensor_count; s++) {
        const uint32_t bit = 1u << s;
        if (!(required & bit))
            continue;
        double r[9];
        quat_to_mat3(r, stats[s].mean_quat);
        if (step == MOCAP_CALIBRATION_HEADING) {
            /* Sensor X lies along the user's forward direction: its heading is the yaw that
             * takes world X onto it. */
            double yaw = atan2(r[3], r[0]);
            double a[9], rz[9], w[9];
            mocap_world_zup_to_model(a);
            mat3_rotation_z(rz, -yaw);
            mat3_multiply(w, a, rz);
            store_mat(next.world_to_model[s], w);
            next.heading_mask |= bit;
            /* The sensors were off the body for this step: any mounting rotation measured
             * before belongs to a different strapping and must be redone. */
            next.valid_mask &= ~bit;
        } else if (step == MOCAP_CALIBRATION_TPOSE) {
            double w[9], sb[9], f[3];
            load_mat(w, cal->world_to_model[s]);
            mat3_multiply(sb, w, r);
            mat3_orthonormalize(sb);
            store_mat(next.sensor_to_bone[s], sb);
            mat3_apply(f, w, stats[s].mean_force);
            for (int i = 0; i < 3; i++)
                next.acceleration_offset[s][i] = (float)f[i];
            next.valid_mask |= bit;
        } else {
            double w[9], sb[9], bone[9], tmp[9];
            load_mat(w, cal->world_to_model[s]);
            load_mat(sb, cal->sensor_to_bone[s]);
            mat3_multiply(tmp, w, r);
            mat3_multiply_transposed(bone, tmp, sb);
            /* Yaw about model Y of the bone's forward (+Z) axis; Ry(yaw) takes +Z to
             * (sin yaw, 0, cos yaw) and +X to (cos yaw, 0, -sin yaw). */
            double fx = bone[2], fz = bone[8];
            double yaw;
            if (sqrt(fx * fx + fz * fz) >= HEADING_RESET_MIN_HORIZONTAL)
                yaw = atan2(fx, fz);
            else
                yaw = atan2(-bone[6], bone[0]);
            double ry[9];
            mat3_rotation_y(ry, -yaw);
            mat3_multiply(w, ry, w);
            mat3_orthonormalize(w);
            store_mat(next.world_to_model[s], w);
        }
    }
    *cal = next;
    report->state = MOCAP_CALIBRATION_ACCEPTED;
    report->reason[0] = '\0';
    acc->state = MOCAP_CALIBRATION_ACCEPTED;
    return MOCAP_OK;
}

void calib_progress(const calib_accumulator *acc, double now_t, mocap_calibration_report *report)
{
    if (acc->step < 0)
        return; /* idle or finished: calib_finish's report stands */
    report->step = acc->step;
    report->sensor_count = acc->sensor_count;
    const int started = acc->start_t >= 0.0 && now_t >= acc->start_t &&
                        acc->state == MOCAP_CALIBRATION_COLLECTING;
    if (!started) {
        report->state = MOCAP_CALIBRATION_WAITING;
        report->progress = 0.0f;
        double wait = acc->start_t >= 0.0 && now_t < acc->start_t ? acc->start_t - now_t : 0.0;
        report->seconds_remaining = (float)(wait + acc->duration);
    } else {
        report->state = MOCAP_CALIBRATION_COLLECTING;
        double p = acc->duration > 0.0 ? (now_t - acc->start_t) / acc->duration : 1.0;
        report->progress = (float)(p < 0.0 ? 0.0 : (p > 1.0 ? 1.0 : p));
        double left = acc->start_t + acc->duration - now_t;
        report->seconds_remaining = (float)(left > 0.0 ? left : 0.0);
    }
    /* Live feedback while collecting, so a UI can say which sensor is moving. The spread needs a
     * pass over the kept orientations and is left for calib_finish. */
    for (int s = 0; s < (int)acc->sensor_count; s++) {
        sensor_stats st;
        compute_stats(acc, s, 0, &st);
        mocap_sensor_quality *q = &report->sensors[s];
        q->segment = acc->segments[s];
        q->samples = st.n;
        q->gyro_rms_dps = (float)st.gyro_rms_dps;
        q->accel_norm_error = (float)st.accel_norm_error;
        q->tilt_deg = (float)st.tilt_deg;
        q->orientation_spread_deg = 0.0f;
        q->ok = (st.n > 0 && st.gyro_rms_dps <= CALIB_MAX_GYRO_RMS_DPS) ? 1 : 0;
    }
}

/* ---- applying ---- */

void calib_identity(mocap_calibration *cal, uint32_t sensor_count, const int32_t *segments)
{
    memset(cal, 0, sizeof *cal);
    cal->struct_size = (uint32_t)sizeof *cal;
    cal->sensor_count = sensor_count;
    if (segments) memcpy(cal->segments, segments, sensor_count * sizeof *segments);
    double id[9];
    mat3_identity(id);
    for (int s = 0; s < MOCAP_MAX_SENSORS; s++) {
        store_mat(cal->world_to_model[s], id);
        store_mat(cal->sensor_to_bone[s], id);
    }
}

void calib_apply(const mocap_calibration *cal, int32_t world_frame, uint32_t optional_mask,
                 const raw_frame *in, mocap_frame *out)
{
    const uint32_t n = cal->sensor_count;
    const uint32_t all = first_sensors(n);
    const uint32_t required = all & ~optional_mask;
    out->sequence = in->sequence;
    out->time_s = in->t;
    out->fresh_mask = in->fresh_mask & all;
    out->sensor_count = n;
    out->reserved = 0;
    out->flags = 0;
    if (required ? (cal->valid_mask & required) == required : (cal->valid_mask & all) != 0)
        out->flags |= MOCAP_FRAME_CALIBRATED;
    if ((in->fresh_mask & all) == all)
        out->flags |= MOCAP_FRAME_COMPLETE;
    memset(&out->sensors[n], 0, (MOCAP_MAX_SENSORS - n) * sizeof out->sensors[0]);

    double conventional[9];
    conventional_world_to_model(world_frame, conventional);

    for (uint32_t s = 0; s < n; s++) {
        const uint32_t bit = 1u << s;
        mocap_sensor_frame *o = &out->sensors[s];
        const int valid = (in->valid_mask & bit) != 0;
        o->segment = cal->segments[s];
        for (int i = 0; i < 4; i++)
            o->sensor_orientation[i] = (float)in->quat[s][i];
        for (int i = 0; i < 3; i++) {
            o->world_specific_force[i] = (float)in->force_world[s][i];
            o->angular_rate[i] = (float)in->gyr[s][i];
        }
        o->age_s = (float)(in->age[s] > 0.0 ? in->age[s] : 0.0);
        o->node_id = in->node_id[s];
        o->flags = 0;
        if (valid) {
            o->flags |= MOCAP_SENSOR_VALID;
            if (!(in->fresh_mask & bit))
                o->flags |= MOCAP_SENSOR_HELD;
        }
        if (in->stale_mask & bit)
            o->flags |= MOCAP_SENSOR_STALE;
        o->state = !valid                       ? MOCAP_SENSOR_ABSENT
                   : (in->stale_mask & bit)     ? MOCAP_SENSOR_SILENT
                   : !(in->fresh_mask & bit)    ? MOCAP_SENSOR_HOLDING
                                                : MOCAP_SENSOR_FRESH;

        double bone_q[4];
        quat_identity(bone_q);
        double bone_a[3] = {0.0, 0.0, 0.0};
        if (valid) {
            double r[9], w[9], bone[9];
            quat_to_mat3(r, in->quat[s]);
            if (cal->valid_mask & bit) {
                double sb[9], tmp[9], f[3];
                load_mat(w, cal->world_to_model[s]);
                load_mat(sb, cal->sensor_to_bone[s]);
                mat3_multiply(tmp, w, r);
                mat3_multiply_transposed(bone, tmp, sb);
                mat3_apply(f, w, in->force_world[s]);
                for (int i = 0; i < 3; i++)
                    bone_a[i] = f[i] - (double)cal->acceleration_offset[s][i];
                o->flags |= MOCAP_SENSOR_CALIBRATED;
            } else {
                /* Preview before calibration: the sensor's own orientation in the model frame,
                 * upright and facing the heading step's (or the world's conventional) forward,
                 * with no mounting correction and no acceleration. */
                if (cal->heading_mask & bit)
                    load_mat(w, cal->world_to_model[s]);
                else
                    memcpy(w, conventional, sizeof w);
                mat3_multiply(bone, w, r);
            }
            mat3_to_quat(bone_q, bone);
        }
        for (int i = 0; i < 4; i++)
            o->bone_orientation[i] = (float)bone_q[i];
        for (int i = 0; i < 3; i++)
            o->bone_acceleration[i] = (float)bone_a[i];
    }
}

/* ---- file format ---- */

typedef enum key_kind { KEY_MASK, KEY_MATRIX, KEY_VECTOR } key_kind;

/* Every key the file must hold, in the order calib_save writes them. */
typedef struct file_key {
    char name[40];
    key_kind kind;
    int segment;
    int which; /* KEY_MASK: 0 valid, 1 heading; KEY_MATRIX: 0 world_to_model, 1 sensor_to_bone */
} file_key;

#define FILE_KEY_MAX (2 + 3 * MOCAP_MAX_SENSORS)

/* key->segment is the entry index (not the segment): the entry's name prefixes the key. */
static void set_key(file_key *key, key_kind kind, const mocap_calibration *cal, int entry,
                    int which, const char *suffix)
{
    if (entry < 0)
        snprintf(key->name, sizeof key->name, "%s", suffix);
    else
        snprintf(key->name, sizeof key->name, "%s.%s",
                 segments_name_or(cal->segments[entry], "unknown"), suffix);
    key->kind = kind;
    key->segment = entry;
    key->which = which;
}

/* The keys a file of cal's sensors holds, in writing order; returns how many. */
static int build_keys(const mocap_calibration *cal, file_key keys[FILE_KEY_MAX])
{
    int k = 0;
    set_key(&keys[k++], KEY_MASK, cal, -1, 0, "valid_mask");
    set_key(&keys[k++], KEY_MASK, cal, -1, 1, "heading_mask");
    for (int s = 0; s < (int)cal->sensor_count; s++) {
        set_key(&keys[k++], KEY_MATRIX, cal, s, 0, "world_to_model");
        set_key(&keys[k++], KEY_MATRIX, cal, s, 1, "sensor_to_bone");
        set_key(&keys[k++], KEY_VECTOR, cal, s, 0, "acceleration_offset");
    }
    return k;
}

/* Largest deviation of m from a proper rotation: |m m^T - I| entries and |det - 1|. */
static double rotation_error(const float mf[9])
{
    double m[9], p[9];
    load_mat(m, mf);
    mat3_multiply_transposed(p, m, m);
    double worst = 0.0;
    for (int i = 0; i < 9; i++) {
        double e = fabs(p[i] - ((i % 4) == 0 ? 1.0 : 0.0));
        if (!(e <= worst))
            worst = e; /* NaN propagates as "bad" */
    }
    double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                 m[2] * (m[3] * m[7] - m[4] * m[6]);
    double e = fabs(det - 1.0);
    if (!(e <= worst))
        worst = e;
    return worst;
}

static mocap_status open_failure(const char *path, const char *what, int err)
{
    char text[128];
    mocap_errno_text(err, text, sizeof text);
    mocap_status st = err == ENOENT ? MOCAP_ERR_NOT_FOUND
                      : (err == EACCES || err == EPERM) ? MOCAP_ERR_PERMISSION
                                                        : MOCAP_ERR_IO;
    return mocap_fail(st, "calibration file %s: cannot %s: %s", path, what, text);
}

int calib_check(const mocap_calibration *cal, char *why, size_t cap)
{
    if (cal->sensor_count < 1 || cal->sensor_count > MOCAP_MAX_SENSORS) {
        snprintf(why, cap, "sensor_count %u is outside 1..%d", (unsigned)cal->sensor_count,
                 MOCAP_MAX_SENSORS);
        return -1;
    }
    const uint32_t all = first_sensors(cal->sensor_count);
    if ((cal->valid_mask & ~all) || (cal->heading_mask & ~all)) {
        snprintf(why, cap, "masks 0x%x/0x%x name sensors beyond %u", (unsigned)cal->valid_mask,
                 (unsigned)cal->heading_mask, (unsigned)cal->sensor_count);
        return -1;
    }
    for (uint32_t s = 0; s < cal->sensor_count; s++) {
        if (!mocap_segment_name(cal->segments[s])) {
            snprintf(why, cap, "entry %u: segment %d is not a known segment", (unsigned)s,
                     cal->segments[s]);
            return -1;
        }
        if (segments_index_of(cal->segments, s, cal->segments[s]) >= 0) {
            snprintf(why, cap, "segment %s appears twice", mocap_segment_name(cal->segments[s]));
            return -1;
        }
    }
    if (cal->valid_mask & ~cal->heading_mask) {
        snprintf(why, cap, "valid_mask 0x%x has sensors without a heading (heading_mask 0x%x)",
                 (unsigned)cal->valid_mask, (unsigned)cal->heading_mask);
        return -1;
    }
    file_key keys[FILE_KEY_MAX];
    const int key_count = build_keys(cal, keys);
    for (int k = 0; k < key_count; k++) {
        const file_key *key = &keys[k];
        if (key->kind == KEY_MATRIX) {
            const float *m = key->which == 0 ? cal->world_to_model[key->segment]
                                             : cal->sensor_to_bone[key->segment];
            for (int i = 0; i < 9; i++) {
                if (!isfinite(m[i])) {
                    snprintf(why, cap, "%s has NaN/Inf", key->name);
                    return -1;
                }
            }
            double e = rotation_error(m);
            if (!(e <= ORTHONORMAL_TOLERANCE)) {
                snprintf(why, cap, "%s is not a rotation (error %g)", key->name, e);
                return -1;
            }
        } else if (key->kind == KEY_VECTOR) {
            for (int i = 0; i < 3; i++) {
                if (!isfinite(cal->acceleration_offset[key->segment][i])) {
                    snprintf(why, cap, "%s is not finite (NaN/Inf)", key->name);
                    return -1;
                }
            }
        }
    }
    return 0;
}

mocap_status calib_save(const mocap_calibration *cal, const char *path)
{
    if (!cal || !path || !path[0])
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration save: NULL calibration or path");
    /* Refuse to write what calib_load would refuse to read. */
    char why[160];
    if (calib_check(cal, why, sizeof why) != 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration save %s: %s", path, why);
    file_key keys[FILE_KEY_MAX];
    const int key_count = build_keys(cal, keys);

    /* Write a sibling file and rename it over the target, so a crash or a full disk never
     * leaves a half-written calibration behind. The target is the file itself: through a
     * symbolic link (the link stays), and never a device, pipe or folder (the rename would
     * replace /dev/full with a regular file, for example). */
    char target[4096];
    int resolve_err = mocap_replace_target(path, target, sizeof target);
    if (resolve_err == -1)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "calibration file %s: not a regular file (a device, pipe or folder); "
                          "not replaced", path);
    if (resolve_err != 0) {
        char text[128];
        mocap_errno_text(resolve_err, text, sizeof text);
        return mocap_fail(MOCAP_ERR_IO, "calibration file %s: cannot tell what to replace: %s", path, text);
    }
    path = target;
    /* Named per process and per call: two saves to one path at once (the API allows any
     * thread) must not write into one temporary file. */
    static mocap_atomic_u64 save_counter;
    char tmp[4096];
    int n = snprintf(tmp, sizeof tmp, "%s.%lu-%llu.tmp", path, mocap_process_id(),
                     (unsigned long long)mocap_atomic_add_u64(&save_counter, 1));
    if (n < 0 || (size_t)n >= sizeof tmp)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration save: path is too long");
    /* Binary: the same bytes ('\n' line ends) on every OS, so a file moves between them. */
    FILE *f = mocap_fopen(tmp, "wb");
    if (!f)
        return open_failure(tmp, "create", errno);
    int ok = fprintf(f, "%s %d\n", CALIB_FILE_HEADER, CALIB_FILE_VERSION) > 0;
    ok = ok && fprintf(f, "# com.mocap.imu calibration. Matrices are row-major; world_to_model maps "
                          "the sensor's Z-up world to the Y-up model frame, sensor_to_bone maps "
                          "the sensor frame to its bone; acceleration_offset in m/s^2. Mask bit "
                          "i is the i-th sensor listed.\n") > 0;
    ok = ok && fputs("sensors", f) != EOF;
    for (uint32_t s = 0; ok && s < cal->sensor_count; s++)
        ok = fprintf(f, " %s", mocap_segment_name(cal->segments[s])) > 0;
    ok = ok && fputc('\n', f) != EOF;
    for (int k = 0; ok && k < key_count; k++) {
        const file_key *key = &keys[k];
        if (key->kind == KEY_MASK) {
            ok = fprintf(f, "%s %u\n", key->name,
                         (unsigned)(key->which == 0 ? cal->valid_mask : cal->heading_mask)) > 0;
            continue;
        }
        const float *v = key->kind == KEY_VECTOR ? cal->acceleration_offset[key->segment]
                         : key->which == 0       ? cal->world_to_model[key->segment]
                                                 : cal->sensor_to_bone[key->segment];
        int count = key->kind == KEY_VECTOR ? 3 : 9;
        ok = fprintf(f, "%s", key->name) > 0;
        /* %.9g round-trips every float exactly; '.' in any locale. */
        for (int i = 0; ok && i < count; i++) {
            char number[40];
            text_format_double(number, sizeof number, " %.9g", (double)v[i]);
            ok = fputs(number, f) != EOF;
        }
        ok = ok && fputc('\n', f) != EOF;
    }
    int err = errno;
    if (ok) {
        const int flush_err = mocap_flush_to_disk(f);
        if (flush_err != 0) {
            ok = 0;
            err = flush_err;
        }
    }
    if (fclose(f) != 0 && ok) {
        ok = 0;
        err = errno;
    }
    if (!ok) {
        mocap_remove_file(tmp);
        char text[128];
        mocap_errno_text(err, text, sizeof text);
        return mocap_fail(MOCAP_ERR_IO, "calibration file %s: write failed: %s", tmp, text);
    }
    err = mocap_replace_file(tmp, path);
    if (err != 0) {
        mocap_remove_file(tmp);
        char text[128];
        mocap_errno_text(err, text, sizeof text);
        return mocap_fail(MOCAP_ERR_IO, "calibration file %s: cannot replace it: %s", path, text);
    }
    return MOCAP_OK;
}

/* Parses exactly count finite numbers from s; anything left over is an error. The values are
 * stored as floats, so a finite double beyond float range counts as not finite: it would turn
 * into infinity, which calib_save (rightly) refuses to write back. */
static int parse_numbers(const char *s, double *out, int count)
{
    for (int i = 0; i < count; i++) {
        char *end;
        errno = 0;
        double v = text_strtod(s, &end);
        if (end == s || !isfinite(v) || fabs(v) > FLT_MAX)
            return 0;
        out[i] = v;
        s = end;
    }
    while (*s == ' ' || *s == '\t')
        s++;
    return *s == '\0';
}

mocap_status calib_load(const char *path, mocap_calibration *out)
{
    if (!path || !path[0] || !out)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration load: NULL path or output");
    FILE *f = mocap_fopen(path, "r");
    if (!f)
        return open_failure(path, "open", errno);

    file_key keys[FILE_KEY_MAX];
    int key_count = 0;
    int seen_line[FILE_KEY_MAX] = {0};
    mocap_calibration cal;
    calib_identity(&cal, 0, NULL);

    char line[1024];
    int line_no = 0, have_header = 0, have_sensors = 0, version = 0;
    mocap_status st = MOCAP_OK;
    while (fgets(line, sizeof line, f)) {
        line_no++;
        size_t len = strlen(line);
        if (len == sizeof line - 1 && line[len - 1] != '\n' && !feof(f)) {
            st = mocap_fail(MOCAP_ERR_FORMAT, "calibration file %s line %d: line too long", path,
                            line_no);
            break;
        }
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r' ||
                           line[len - 1] == ' ' || line[len - 1] == '\t'))
            line[--len] = '\0';
        if (!have_header) {
            char name[32];
            char extra;
            int fields = sscanf(line, "%31s %d %c", name, &version, &extra);
            if (fields < 1 || strcmp(name, CALIB_FILE_HEADER) != 0) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "calibration file %s line %d: not a calibration file (expected "
                                "\"%s %d\")", path, line_no, CALIB_FILE_HEADER, CALIB_FILE_VERSION);
                break;
            }
            if (fields != 2 || version < 1 || version > CALIB_FILE_VERSION) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "calibration file %s line %d: unsupported version \"%s\" (this "
                                "build reads versions 1..%d)", path, line_no,
                                line + strlen(CALIB_FILE_HEADER), CALIB_FILE_VERSION);
                break;
            }
            have_header = 1;
            if (version == 1) {
                cal.sensor_count = (uint32_t)(sizeof VERSION1_SENSORS / sizeof VERSION1_SENSORS[0]);
                for (uint32_t s = 0; s < cal.sensor_count; s++)
                    cal.segments[s] = mocap_segment_find(VERSION1_SENSORS[s]);
                key_count = build_keys(&cal, keys);
                have_sensors = 1;
            }
            continue;
        }
        const char *p = line;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == '\0' || *p == '#')
            continue;
        size_t key_len = strcspn(p, " \t");
        if (!have_sensors) {
            if (key_len != 7 || strncmp(p, "sensors", 7) != 0) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "calibration file %s line %d: expected the \"sensors\" line "
                                "before \"%.*s\"", path, line_no,
                                (int)(key_len > 60 ? 60 : key_len), p);
                break;
            }
            const char *q = p + key_len;
            for (;;) {
                while (*q == ' ' || *q == '\t') q++;
                if (!*q) break;
                size_t n = strcspn(q, " \t");
                char name[40];
                snprintf(name, sizeof name, "%.*s", (int)(n < 39 ? n : 39), q);
                int32_t seg = mocap_segment_find(name);
                if (seg < 0 || n >= sizeof name) {
                    st = mocap_fail(MOCAP_ERR_FORMAT,
                                    "calibration file %s line %d: \"%s\" is not a segment this "
                                    "build knows", path, line_no, name);
                    break;
                }
                if (segments_index_of(cal.segments, cal.sensor_count, seg) >= 0 ||
                    cal.sensor_count == MOCAP_MAX_SENSORS) {
                    st = mocap_fail(MOCAP_ERR_FORMAT,
                                    "calibration file %s line %d: %s%s", path, line_no,
                                    cal.sensor_count == MOCAP_MAX_SENSORS
                                        ? "more sensors than the engine carries"
                                        : "a segment is listed twice: ",
                                    cal.sensor_count == MOCAP_MAX_SENSORS ? "" : name);
                    break;
                }
                cal.segments[cal.sensor_count++] = seg;
                q += n;
            }
            if (st != MOCAP_OK) break;
            if (cal.sensor_count == 0) {
                st = mocap_fail(MOCAP_ERR_FORMAT, "calibration file %s line %d: no sensors listed",
                                path, line_no);
                break;
            }
            key_count = build_keys(&cal, keys);
            have_sensors = 1;
            continue;
        }
        int k = 0;
        for (; k < key_count; k++)
            if (strlen(keys[k].name) == key_len && strncmp(keys[k].name, p, key_len) == 0)
                break;
        if (k == key_count) {
            st = mocap_fail(MOCAP_ERR_FORMAT, "calibration file %s line %d: unknown key \"%.*s\"",
                            path, line_no, (int)(key_len > 60 ? 60 : key_len), p);
            break;
        }
        if (seen_line[k]) {
            st = mocap_fail(MOCAP_ERR_FORMAT,
                            "calibration file %s line %d: %s repeated (first on line %d)", path,
                            line_no, keys[k].name, seen_line[k]);
            break;
        }
        seen_line[k] = line_no;
        const char *values = p + key_len;
        const file_key *key = &keys[k];
        if (key->kind == KEY_MASK) {
            char *end;
            errno = 0;
            unsigned long v = strtoul(values, &end, 10);
            while (*end == ' ' || *end == '\t')
                end++;
            if (end == values || *end != '\0' || errno != 0 || v > first_sensors(cal.sensor_count)) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "calibration file %s line %d: %s must be an integer 0..%u", path,
                                line_no, key->name, first_sensors(cal.sensor_count));
                break;
            }
            if (key->which == 0)
                cal.valid_mask = (uint32_t)v;
            else
                cal.heading_mask = (uint32_t)v;
            continue;
        }
        int count = key->kind == KEY_VECTOR ? 3 : 9;
        double v[9];
        if (!parse_numbers(values, v, count)) {
            st = mocap_fail(MOCAP_ERR_FORMAT,
                            "calibration file %s line %d: %s needs %d finite numbers", path,
                            line_no, key->name, count);
            break;
        }
        float *dst = key->kind == KEY_VECTOR ? cal.acceleration_offset[key->segment]
                     : key->which == 0       ? cal.world_to_model[key->segment]
                                             : cal.sensor_to_bone[key->segment];
        for (int i = 0; i < count; i++)
            dst[i] = (float)v[i];
        if (key->kind == KEY_MATRIX) {
            double e = rotation_error(dst);
            if (!(e <= ORTHONORMAL_TOLERANCE)) {
                st = mocap_fail(MOCAP_ERR_FORMAT,
                                "calibration file %s line %d: %s is not a rotation matrix "
                                "(off by %.3g)", path, line_no, key->name, e);
                break;
            }
        }
    }
    int read_error = ferror(f);
    fclose(f);
    if (st != MOCAP_OK)
        return st;
    if (read_error)
        return mocap_fail(MOCAP_ERR_IO, "calibration file %s: read failed after line %d", path,
                          line_no);
    if (!have_header)
        return mocap_fail(MOCAP_ERR_FORMAT, "calibration file %s line 1: empty file", path);
    if (!have_sensors)
        return mocap_fail(MOCAP_ERR_FORMAT,
                          "calibration file %s line %d (end of file): the sensors line is missing",
                          path, line_no + 1);
    for (int k = 0; k < key_count; k++)
        if (!seen_line[k])
            return mocap_fail(MOCAP_ERR_FORMAT,
                              "calibration file %s line %d (end of file): key %s is missing",
                              path, line_no + 1, keys[k].name);
    if (cal.valid_mask & ~cal.heading_mask)
        return mocap_fail(MOCAP_ERR_FORMAT,
                          "calibration file %s line %d: valid_mask 0x%x has sensors without a "
                          "heading (heading_mask 0x%x)", path, seen_line[0],
                          (unsigned)cal.valid_mask, (unsigned)cal.heading_mask);
    *out = cal;
    return MOCAP_OK;
}
