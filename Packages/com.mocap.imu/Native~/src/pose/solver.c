/* The pose solver: one inference thread, several characters batched per tick. See solver.h for
 * the scheduling and mocap_imu.h for the public contract. Root motion: drift.h. FK:
 * skeleton_fk.h. */
#include "solver.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "drift.h"
#include "foot_pin.h"
#include "pose_limits.h"
#include "chest_follow.h"
#include "error.h"
#include "mocap_math.h"
#include "platform.h"
#include "pose_filter.h"
#include "session_internal.h"
#include "skeleton_fk.h"
#include "spsc_ring.h"

#define POSE_RING_POSES 1024   /* 17 s at 60 Hz for a consumer that drains rarely */
#define FRAME_BUFFER 16        /* frames taken from a session per drain call */
#define ABSENT_PERIODS 3       /* no frame for this many periods: not waited for */

/* A solved frame waiting for the frames after it (smoothing that waits). */
typedef struct waiting_frame {
    double q[MOCAP_JOINT_COUNT][4];   /* the network's rotations, not smoothed */
    float vel[3], contact[2];
    uint64_t sequence;
    double time_s;
    int64_t newest_receive_ns, emitted_ns, taken_ns;
    int fresh;                        /* every model sensor was fresh (else INCOMPLETE) */
    int held;                         /* non-finite input or output: the pose before repeats */
} waiting_frame;

#define WAITING_FRAMES (2 * MOCAP_SMOOTHING_DELAY_MAX + 1)

typedef struct character {
    mocap_session *session;
    int replay;                 /* frames are stamped with data time, not the wall clock */
    int replay_fast;            /* back-pressure instead of dropping */
    spsc_ring poses;
    float *state_h, *state_c;   /* [L][H] each: this character's recurrent state */
    /* Model sensor k comes from the session's sensor slot_of[k]; -1: the session has none. */
    int8_t slot_of[MOCAP_MAX_SENSORS];

    /* Solver thread only. */
    mocap_frame buf[FRAME_BUFFER];
    uint32_t buf_count, buf_pos;
    int64_t buf_taken_ns;       /* when buf left the session */
    const mocap_frame *pending; /* next frame to solve (points into buf) */
    int session_ended;
    int64_t last_frame_ns;      /* monotonic time a frame last became pending (0: never) */
    drift_state drift;
    foot_pin_state pin;
    pose_limits_state limits;
    pose_filter_state smoothing;
    /* Smoothing that waits: the last frames, oldest first; waiting[next_emit] is the next to
     * become a pose (the ones before it are poses already). */
    waiting_frame waiting[WAITING_FRAMES];
    int waiting_count, next_emit;
    uint64_t pose_sequence;
    int have_last_pose;
    mocap_pose last_pose;
    /* The global orientation of each model sensor's bone in the last model output: what a
     * silent sensor is fed in its place (stand_in_silent_sensors; have_bones: there was an
     * output). */
    int have_bones;
    float bone_rot[MOCAP_MAX_SENSORS][9];
    /* Each sensor's horizontal heading vector (x, z) at the pelvis' last fresh sample;
     * have_headings: bit k known. */
    uint32_t have_headings;
    float heading_ref[MOCAP_MAX_SENSORS][2];
    /* The pelvis' heading (rad) at each wrist's last fresh sample; bit k: known. */
    float pelvis_heading_at[MOCAP_MAX_SENSORS];
    uint32_t have_pelvis_heading_at;
    /* Model frames each sensor has been silent for (settle_silent_sensors). */
    int32_t silent_frames[MOCAP_MAX_SENSORS];
    /* Ease back from a stand-in (ease_returning_sensors): bit k of stood_in, sensor k was fed one
     * in the last frame (stand_in_rot); of returning, it is live again and its stand-in's offset
     * (return_offset, stand-in times live^-1) is fading out, returned_frames frames in. */
    uint32_t stood_in, returning;
    float stand_in_rot[MOCAP_MAX_SENSORS][9];
    double return_offset[MOCAP_MAX_SENSORS][4];
    int32_t returned_frames[MOCAP_MAX_SENSORS];

    mocap_atomic_int ended;     /* the session ended and every pose was pushed */
    mocap_atomic_int reset_requested;
    /* The root velocity's factor for the performer's height (a double's bits; 1 by default). */
    mocap_atomic_u64 velocity_gain_bits;
    mocap_atomic_u64 frames_solved, frames_uncalibrated, frames_nonfinite, outputs_nonfinite,
        poses_dropped, run_failures;

    /* Every pose is also published here: the newest one, for poll_latest, even while the ring
     * is full after a long pause of the consumer (the ring keeps the oldest). */
    triple_buffer newest_pose;

    /* Consumer only: the newest pose handed out by poll or drain (have_latest: one was);
     * poses with its sequence or an older one are not handed out again. */
    int have_latest;
    mocap_pose latest;
} character;

struct mocap_solver {
    mocap_model *model;
    mocap_model_info info;
    mocap_solver_config config;
    skeleton sk;
    drift_params drift;
    foot_pin_params pin;
    double pose_limit_deg;      /* the pose guard's tolerance (0: off) */
    double chest_follow;        /* share of the way the spine turns to a chest sensor (0: off) */
    pose_filter_params smoothing;
    int smoothing_delay;        /* frames the centred window waits for (0: the one-euro filter) */
    double smoothing_weights[WAITING_FRAMES]; /* its binomial weights */
    int L, H;
    int64_t period_ns;
    character *chars[MOCAP_MAX_CHARACTERS];
    int count;
    ort_stream *streams[MOCAP_MAX_CHARACTERS]; /* [B - 1] */
    int prepared, started;
    mocap_thread *thread;
    mocap_atomic_int stop;
    solver_input_tap tap;
    void *tap_user;

    /* Scratch of one tick (solver thread). */
    int32_t tick_chars[MOCAP_MAX_CHARACTERS];
    const mocap_frame *tick_frames[MOCAP_MAX_CHARACTERS];
    int64_t tick_taken[MOCAP_MAX_CHARACTERS];
    int batch_index[MOCAP_MAX_CHARACTERS];     /* tick entry of batch slot b */
    int sensors;                /* N: the model's sensor count */
    int with_mask;              /* the model takes the mask (contract 2, or 3 with masked features) */
    int pelvis_index;           /* the model's pelvis sensor (-1: none) */
    int chest_index;            /* the model's sensor on the chest bone, spine3 (-1: none) */
    float in_ori[MOCAP_MAX_CHARACTERS][MOCAP_MAX_SENSORS * 9];
    float in_acc[MOCAP_MAX_CHARACTERS][MOCAP_MAX_SENSORS * 3];
    float in_mask[MOCAP_MAX_CHARACTERS][MOCAP_MAX_SENSORS];
    mocap_pose pose;

    mocap_atomic_u64 ticks, batched_calls, max_batch, solve_ns_total, solve_ns_max, run_ns_total;

    /* Inference failures: written by the solver thread, read by any (mocap_solver_get_stats). */
    mocap_mutex *error_lock;
    int32_t last_run_status;
    char first_run_error[256], last_run_error[256];
};

/* ---------------------------------------------------------------------------------------- */
/* Inputs                                                                                      */

int solver_frame_input(const mocap_frame *f, const int8_t *slot_of, int sensors, int with_mask,
                       float *orientation, float *acceleration, float *mask)
{
    for (int k = 0; k < sensors; ++k) {
        const int slot = slot_of[k];
        const mocap_sensor_frame *sf = slot >= 0 && slot < (int)f->sensor_count ? &f->sensors[slot]
                                                                               : NULL;
        /* Contract 1 has no way to say "missing": its sensors are all required, so a slot
         * always exists and a silent sensor is fed its held value, as the frame carries it. A
         * masked model is told "missing" only for a sensor it has nothing of (absent from the
         * session, never sent, or uncalibrated): a silent one is fed its held value too, which
         * the stand-ins below replace, since they served even a model trained with sensors
         * dropping out better than the mask did (stand_in_silent_sensors). */
        int present = sf != NULL;
        if (with_mask && sf)
            present = (sf->flags & MOCAP_SENSOR_CALIBRATED) && sf->state != MOCAP_SENSOR_ABSENT;
        if (mask) mask[k] = present ? 1.0f : 0.0f;
        if (!present) {
            memset(orientation + k * 9, 0, 9 * sizeof(float));
            memset(acceleration + k * 3, 0, 3 * sizeof(float));
            continue;
        }
        double q[4];
        for (int i = 0; i < 4; ++i) {
            if (!isfinite(sf->bone_orientation[i])) return -1;
            q[i] = sf->bone_orientation[i];
        }
        for (int i = 0; i < 3; ++i)
            if (!isfinite(sf->bone_acceleration[i])) return -1;
        if (quat_normalize(q) != 0) return -1;
        double m[9];
        quat_to_mat3(m, q);
        for (int i = 0; i < 9; ++i) orientation[k * 9 + i] = (float)m[i];
        for (int i = 0; i < 3; ++i) acceleration[k * 3 + i] = sf->bone_acceleration[i];
    }
    return 0;
}

/* Model sensor k's entry of f, or NULL where the session has no such sensor. */
static const mocap_sensor_frame *model_sensor(const character *ch, const mocap_frame *f, int k)
{
    const int slot = ch->slot_of[k];
    return slot >= 0 && slot < (int)f->sensor_count ? &f->sensors[slot] : NULL;
}

/* Whether the model's required sensors are calibrated in f (require_calibration). */
static int required_calibrated(const mocap_solver *s, const character *ch, const mocap_frame *f)
{
    for (int k = 0; k < s->sensors; ++k) {
        if (!(s->info.sensor_required_mask & (1u << k))) continue;
        const mocap_sensor_frame *sf = model_sensor(ch, f, k);
        if (!sf || !(sf->flags & MOCAP_SENSOR_CALIBRATED)) return 0;
    }
    return 1;
}

/* Whether every model sensor had a fresh sample for f. */
static int model_sensors_fresh(const mocap_solver *s, const character *ch, const mocap_frame *f)
{
    for (int k = 0; k < s->sensors; ++k) {
        const mocap_sensor_frame *sf = model_sensor(ch, f, k);
        if (!sf || sf->state != MOCAP_SENSOR_FRESH) return 0;
    }
    return 1;
}

static int all_finite(const float *v, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* ---------------------------------------------------------------------------------------- */
/* Poses                                                                                       */

static int64_t pose_stamp(const character *ch, const mocap_frame *f, int64_t taken_ns)
{
    int64_t now = mocap_monotonic_ns();
    /* Live frames are stamped on the monotonic clock: the pose is stamped on it too. A replay's
     * frames carry recorded times: the pose is the frame's stamp plus the real time the frame
     * spent in the solver (waiting + inference), so pose - frame is still the solver latency. */
    if (!ch->replay) return now;
    return f->emitted_ns + (now - taken_ns);
}

static void push_pose(character *ch, const mocap_pose *pose)
{
    *(mocap_pose *)triple_buffer_write_slot(&ch->newest_pose) = *pose;
    triple_buffer_publish(&ch->newest_pose);
    mocap_pose *slot = (mocap_pose *)spsc_ring_reserve(&ch->poses);
    if (!slot) {
        mocap_atomic_add_u64(&ch->poses_dropped, 1);
        return;
    }
    *slot = *pose;
    spsc_ring_commit(&ch->poses);
}

static uint64_t double_to_bits(double v)
{
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    return bits;
}

static double bits_to_double(uint64_t bits)
{
    double v;
    memcpy(&v, &bits, sizeof v);
    return v;
}

/* The pose of frame e with rotations q: forward kinematics, root motion and drift correction
 * from e's velocity and contacts, e's stamps. */
static void emit_pose(mocap_solver *s, int32_t c, const waiting_frame *e, double q[][4], int64_t stamp_ns)
{
    character *ch = s->chars[c];
    double rel[MOCAP_JOINT_COUNT][3];
    const double zero[3] = {0, 0, 0};
    /* Again after smoothing: the range is not convex, so a filtered or averaged pose of guarded
     * frames can leave it (40 validation replays, the centred window: 30 poses). */
    if (s->pose_limit_deg > 0.0) pose_limits_apply(&ch->limits, s->pose_limit_deg, q, NULL);
    skeleton_fk(&s->sk, (const double (*)[4])q, zero, NULL, rel);
    if (!ch->drift.initialized) {
        drift_reset(&ch->drift, s->sk.offsets[0]);
        foot_pin_reset(&ch->pin);
    }
    const double gain = bits_to_double(mocap_atomic_load_u64(&ch->velocity_gain_bits));
    double v[3] = {e->vel[0] * gain, e->vel[1] * gain, e->vel[2] * gain};
    double p[2] = {e->contact[0], e->contact[1]};
    double feet[2][3];
    memcpy(feet[0], rel[SKELETON_LEFT_FOOT], sizeof feet[0]);
    memcpy(feet[1], rel[SKELETON_RIGHT_FOOT], sizeof feet[1]);
    double root[3];
    int corrected = drift_step(&ch->drift, &s->drift, v, p, (const double (*)[3])feet, root);
    /* Drift correction reads the feet of the predicted pose; the shown pose holds planted feet. */
    const int planted[2] = {p[0] >= s->drift.contact_threshold, p[1] >= s->drift.contact_threshold};
    if (foot_pin_apply(&ch->pin, &s->pin, &s->sk, root, planted, q) > 0)
        skeleton_fk(&s->sk, (const double (*)[4])q, zero, NULL, rel);

    mocap_pose *pose = &s->pose;
    pose->sequence = ch->pose_sequence++;
    pose->frame_sequence = e->sequence;
    pose->time_s = e->time_s;
    pose->character = (uint32_t)c;
    uint32_t flags = 0;
    if (planted[0]) flags |= MOCAP_POSE_CONTACT_LEFT;
    if (planted[1]) flags |= MOCAP_POSE_CONTACT_RIGHT;
    if (corrected) flags |= MOCAP_POSE_CORRECTED;
    if (!e->fresh) flags |= MOCAP_POSE_INCOMPLETE;
    pose->flags = flags;
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        for (int k = 0; k < 4; ++k) pose->joint_rotations[j][k] = (float)q[j][k];
        for (int k = 0; k < 3; ++k) pose->joint_positions[j][k] = (float)(root[k] + rel[j][k]);
    }
    for (int k = 0; k < 3; ++k) {
        pose->root_position[k] = (float)root[k];
        pose->root_velocity[k] = (float)v[k];
    }
    pose->foot_contact[0] = e->contact[0];
    pose->foot_contact[1] = e->contact[1];
    pose->newest_receive_ns = e->newest_receive_ns;
    pose->frame_emitted_ns = e->emitted_ns;
    pose->pose_emitted_ns = stamp_ns;
    ch->last_pose = *pose;
    ch->have_last_pose = 1;
    push_pose(ch, pose);
}

/* The pose before repeated for frame e, flagged INCOMPLETE (a held frame). */
static void emit_held(character *ch, const waiting_frame *e, int64_t stamp_ns, mocap_pose *p)
{
    if (!ch->have_last_pose) return;
    *p = ch->last_pose;
    p->sequence = ch->pose_sequence++;
    p->frame_sequence = e->sequence;
    p->time_s = e->time_s;
    p->flags = (p->flags & ~(uint32_t)MOCAP_POSE_CORRECTED) | MOCAP_POSE_INCOMPLETE;
    p->newest_receive_ns = e->newest_receive_ns;
    p->frame_emitted_ns = e->emitted_ns;
    p->pose_emitted_ns = stamp_ns;
    push_pose(ch, p);
}

static void waiting_frame_of(waiting_frame *e, const mocap_solver *s, const character *ch,
                             const mocap_frame *f, int64_t taken_ns)
{
    e->sequence = f->sequence;
    e->time_s = f->time_s;
    e->newest_receive_ns = f->newest_receive_ns;
    e->emitted_ns = f->emitted_ns;
    e->taken_ns = taken_ns;
    e->fresh = model_sensors_fresh(s, ch, f);
    e->held = 0;
}

/* Binomial weights of row 2 d (1/4, 1/2, 1/4 for d = 1). */
static void binomial_weights(int d, double *w)
{
    const int n = 2 * d;
    double c = 1.0;
    for (int k = 0; k <= n; ++k) {
        w[k] = c / ldexp(1.0, n);
        c = c * (double)(n - k) / (double)(k + 1);
    }
}

/* Emits the waiting frames whose window is complete, or all of them (flush: the window's far
 * side repeats the newest frame), in frame order. */
static void emit_waiting(mocap_solver *s, int32_t c, int flush)
{
    character *ch = s->chars[c];
    const int d = s->smoothing_delay, n = ch->waiting_count;
    if (n == 0) return;
    const waiting_frame *newest = &ch->waiting[n - 1];
    const int64_t now = mocap_monotonic_ns();
    /* Live: the monotonic clock. A replay: the newest frame's recorded stamp plus the real time
     * it spent here, so pose - frame counts the frames waited for. */
    const int64_t stamp = ch->replay ? newest->emitted_ns + (now - newest->taken_ns) : now;
    const double *w = s->smoothing_weights;
    while (ch->next_emit < n && (flush || ch->next_emit <= n - 1 - d)) {
        const int centre = ch->next_emit++;
        const waiting_frame *e = &ch->waiting[centre];
        if (e->held) {
            emit_held(ch, e, stamp, &s->pose);
            continue;
        }
        double q[MOCAP_JOINT_COUNT][4];
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            double sum[4] = {0, 0, 0, 0};
            for (int o = -d; o <= d; ++o) {
                int i = centre + o;
                i = i < 0 ? 0 : (i > n - 1 ? n - 1 : i);
                const double *qi = ch->waiting[i].q[j];
                /* q and -q are one rotation: average on the centre's hemisphere */
                double dot = 0.0;
                for (int k = 0; k < 4; ++k) dot += qi[k] * e->q[j][k];
                const double sign = dot < 0.0 ? -1.0 : 1.0;
                for (int k = 0; k < 4; ++k) sum[k] += w[o + d] * sign * qi[k];
            }
            double norm = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2] + sum[3] * sum[3]);
            for (int k = 0; k < 4; ++k) q[j][k] = norm > 0.0 ? sum[k] / norm : e->q[j][k];
        }
        emit_pose(s, c, e, q, stamp);
    }
    if (flush) ch->waiting_count = ch->next_emit = 0;
}

/* Adds a solved (or held) frame to the window; the oldest, a pose already, makes room. */
static void wait_for_neighbours(mocap_solver *s, int32_t c, const waiting_frame *e)
{
    character *ch = s->chars[c];
    if (ch->waiting_count == 2 * s->smoothing_delay + 1) {
        memmove(&ch->waiting[0], &ch->waiting[1], (size_t)(ch->waiting_count - 1) * sizeof ch->waiting[0]);
        --ch->waiting_count;
        --ch->next_emit;
    }
    ch->waiting[ch->waiting_count++] = *e;
    emit_waiting(s, c, 0);
}

/* NaN/Inf input or output: nothing reaches the model state; the previous pose is repeated for
 * this frame with MOCAP_POSE_INCOMPLETE set (nothing is emitted before the first pose). */
static void hold_pose(mocap_solver *s, int32_t c, const mocap_frame *f, int64_t taken_ns)
{
    character *ch = s->chars[c];
    if (s->smoothing_delay > 0) {
        if (ch->waiting_count == 0) return;
        waiting_frame e = ch->waiting[ch->waiting_count - 1];
        waiting_frame_of(&e, s, ch, f, taken_ns);
        e.held = 1;
        wait_for_neighbours(s, c, &e);
        return;
    }
    waiting_frame e;
    waiting_frame_of(&e, s, ch, f, taken_ns);
    emit_held(ch, &e, pose_stamp(ch, f, taken_ns), &s->pose);
}

/* Each model sensor's bone, globally, in the model's pose q (joint 0 global, the others local). */
static void keep_sensor_bones(const mocap_solver *s, character *ch, const double (*q)[4])
{
    static const double origin[3] = {0.0, 0.0, 0.0};
    double global[MOCAP_JOINT_COUNT][4], m[9];
    skeleton_fk(&s->sk, q, origin, global, NULL);
    for (int k = 0; k < s->sensors; ++k) {
        const int32_t joint = mocap_segment_joint(s->info.sensor_segments[k]);
        if (joint < 0 || joint >= MOCAP_JOINT_COUNT) continue;
        quat_to_mat3(m, global[joint]);
        for (int i = 0; i < 9; ++i) ch->bone_rot[k][i] = (float)m[i];
    }
    ch->have_bones = 1;
}

/* A silent sensor is fed a stand-in, by every model. A silent shin or head (or any
 * sensor but the pelvis and the wrists) is fed its bone as the model posed it in the frame
 * before, at rest, instead of its last sample, which stays put while the body moves on: legs and
 * head follow the body, and the model's own guess of them is better than the stale sample (15
 * validation clips, 5 s gaps: the silent bone's error 37-40 -> 16-18 deg for a shin, 54 -> 43 for
 * the head; the pose's 10.3-10.5 -> 9.0-9.4 and 10.1 -> 9.7 deg). A hand moves on its own: fed
 * the model's guess the arm wanders further (shoulders more often past 90 deg), so a wrist keeps
 * its held sample, turned with the body (turn_silent_wrists). The pelvis is every other sensor's
 * frame: turn_silent_pelvis. A wrist or head then settles (settle_silent_sensors).
 * A masked model, trained with sensors dropping out, could be told a silent sensor is missing
 * instead, but did better fed the same stand-ins (seven-sensor model, 15 validation clips, 5 s
 * gap, six sensors, angle in the gap / the silent bone's error / new frames past 90 deg: shins
 * 10.5-10.6 / 36 / 62, 38 -> 9.1-9.4 / 15-18 / 18, 17; wrists 9.40, 9.48 / 42, 49 / 177, 382 ->
 * 9.25, 9.54 / 38, 47 / 82, 264; head 9.67 / 34 / 14 -> 9.48 / 28 / 17). The mask is left for
 * sensors there is nothing of (silent_sensor_fed: mask 0 skips them). */
static int silent_sensor_fed(const mocap_sensor_frame *sf, const float *mask, int k)
{
    return sf && sf->state == MOCAP_SENSOR_SILENT && (!mask || mask[k] != 0.0f);
}

static void stand_in_silent_sensors(const mocap_solver *s, const character *ch, const mocap_frame *f,
                                    float *orientation, float *acceleration, const float *mask)
{
    for (int k = 0; k < s->sensors; ++k) {
        const mocap_sensor_frame *sf = model_sensor(ch, f, k);
        if (!silent_sensor_fed(sf, mask, k) || sf->segment == MOCAP_SEGMENT_PELVIS ||
            sf->segment == MOCAP_SEGMENT_LEFT_WRIST || sf->segment == MOCAP_SEGMENT_RIGHT_WRIST)
            continue;
        if (ch->have_bones) memcpy(orientation + k * 9, ch->bone_rot[k], 9 * sizeof(float));
        memset(acceleration + k * 3, 0, 3 * sizeof(float));
    }
}

/* The heading (rad, about +Y) of a bone's forward direction on the floor, as the model reads the
 * pelvis' (its up axis keeps it defined when the forward axis is vertical). */
static void bone_heading_vector(const float *m, float h[2])
{
    h[0] = m[2] - m[5] * m[1];
    h[1] = m[8] - m[5] * m[7];
}

static float bone_heading(const float *m)
{
    float h[2];
    bone_heading_vector(m, h);
    return atan2f(h[0], h[1]);
}

/* A sensor with a sample of its own for this frame (fresh, or held within stale_after_s). */
static int sensor_live(const mocap_sensor_frame *sf)
{
    return sf && (sf->state == MOCAP_SENSOR_FRESH || sf->state == MOCAP_SENSOR_HOLDING);
}

/* m = Ry(angle) m: a rotation turned about the vertical (+Y), the heading growing by angle. */
static void turn_about_vertical(float *m, double angle)
{
    const float cs = (float)cos(angle), sn = (float)sin(angle);
    float out[9];
    for (int col = 0; col < 3; ++col) {
        out[0 * 3 + col] = cs * m[0 * 3 + col] + sn * m[2 * 3 + col];
        out[1 * 3 + col] = m[1 * 3 + col];
        out[2 * 3 + col] = -sn * m[0 * 3 + col] + cs * m[2 * 3 + col];
    }
    memcpy(m, out, sizeof out);
}

/* A silent pelvis is fed its last sample turned about the vertical by how far the shins turned
 * since it was last live (the mean of the live shins' heading changes), with zero acceleration.
 * Every model reads the body in the pelvis' frame, so a pelvis held still while the performer
 * turns turned the whole pose away; the legs carry the pelvis' heading through a turn, and a held
 * acceleration is a constant push the root integrates. 15 validation clips with a 5 s gap: angle
 * 19.3 -> 9.1 deg, the pelvis' own 61.6 -> 9.9, new frames past 90 deg 1521 -> 0, 10 s drift
 * 0.67 -> 0.36 m (the head's turn as well, or instead, did less: training/results/EXPERIMENTS.md). */
static void turn_silent_pelvis(const mocap_solver *s, character *ch, const mocap_frame *f,
                               float *orientation, float *acceleration)
{
    const int pelvis = s->pelvis_index;
    const mocap_sensor_frame *pf = pelvis >= 0 ? model_sensor(ch, f, pelvis) : NULL;
    if (!pf) return;
    if (pf->state == MOCAP_SENSOR_FRESH) {
        /* the references go with the sample a silence will hold, not with a later frame */
        ch->have_headings = 0;
        for (int k = 0; k < s->sensors; ++k) {
            if (!sensor_live(model_sensor(ch, f, k))) continue;
            bone_heading_vector(orientation + k * 9, ch->heading_ref[k]);
            ch->have_headings |= 1u << k;
        }
    }
    if (pf->state != MOCAP_SENSOR_SILENT && pf->state != MOCAP_SENSOR_HOLDING) return;
    if (pf->state == MOCAP_SENSOR_SILENT) memset(acceleration + pelvis * 3, 0, 3 * sizeof(float));
    /* the shins' turns summed as vectors: a shin whose heading is ill-defined (pitched near the
     * vertical, its horizontal vector short) counts for little */
    double sx = 0.0, cx = 0.0;
    for (int k = 0; k < s->sensors; ++k) {
        const int32_t segment = s->info.sensor_segments[k];
        if ((segment != MOCAP_SEGMENT_LEFT_SHIN && segment != MOCAP_SEGMENT_RIGHT_SHIN) ||
            !(ch->have_headings & (1u << k)) || !sensor_live(model_sensor(ch, f, k)))
            continue;
        const float *a = ch->heading_ref[k];
        float b[2];
        bone_heading_vector(orientation + k * 9, b);
        sx += (double)b[0] * a[1] - (double)b[1] * a[0];
        cx += (double)a[0] * b[0] + (double)a[1] * b[1];
    }
    if (sx * sx + cx * cx < 1e-12) return;   /* no shin to follow: not turned */
    turn_about_vertical(orientation + pelvis * 9, atan2(sx, cx));
}

/* A silent wrist is fed its held sample turned about the vertical as far
 * as the pelvis turned since the wrist was last live: a hand held still in the room while the
 * body turns twists against the arm, one turned with the body keeps its pose relative to it (15
 * validation clips, 5 s gap: the pose 10.4 - 11.1 -> 9.3 - 9.9 deg, the silent hand 61 - 76 ->
 * 42 - 55 deg, new frames past 90 deg 450 / 741 -> 318 / 702). settle_silent_sensors then
 * moves it on. */
/* The pelvis' heading is every turn's reference: nothing to turn by when it is not fed. */
static int pelvis_fed(const mocap_solver *s, const float *mask)
{
    return s->pelvis_index >= 0 && (!mask || mask[s->pelvis_index] != 0.0f);
}

static void turn_silent_wrists(const mocap_solver *s, character *ch, const mocap_frame *f,
                               float *orientation, const float *mask)
{
    if (!pelvis_fed(s, mask)) return;
    const float pelvis_now = bone_heading(orientation + s->pelvis_index * 9);
    for (int k = 0; k < s->sensors; ++k) {
        const int32_t segment = s->info.sensor_segments[k];
        const mocap_sensor_frame *sf = model_sensor(ch, f, k);
        if (!sf || (segment != MOCAP_SEGMENT_LEFT_WRIST && segment != MOCAP_SEGMENT_RIGHT_WRIST)) continue;
        if (sf->state == MOCAP_SENSOR_FRESH) {
            ch->pelvis_heading_at[k] = pelvis_now;
            ch->have_pelvis_heading_at |= 1u << k;
        }
        if ((sf->state != MOCAP_SENSOR_HOLDING && !silent_sensor_fed(sf, mask, k)) ||
            !(ch->have_pelvis_heading_at & (1u << k)))
            continue;
        turn_about_vertical(orientation + k * 9, (double)pelvis_now - (double)ch->pelvis_heading_at[k]);
    }
}

/* The usual orientation of a bone in the frame of the pelvis' heading: the chordal mean over
 * every 4th training clip (python3 -m training usual-orientation). */
static const float USUAL_LEFT_WRIST[9] = {-0.0718f, 0.8356f, -0.5446f, -0.3233f, 0.4970f,
                                          0.8053f,  0.9436f, 0.2339f,  0.2345f};
static const float USUAL_RIGHT_WRIST[9] = {-0.0721f, -0.7129f, 0.6976f, 0.2907f, 0.6540f,
                                           0.6984f,  -0.9541f, 0.2531f, 0.1600f};
static const float USUAL_HEAD[9] = {0.9984f, -0.0092f, -0.0555f, 0.0001f, 0.9871f,
                                    -0.1602f, 0.0563f, 0.1599f, 0.9855f};
/* Seconds of silence after which a settling sensor is fed its bone's usual orientation alone. */
#define SILENT_SETTLE_S 4.0

static const float *usual_orientation(int32_t segment)
{
    switch (segment) {
    case MOCAP_SEGMENT_LEFT_WRIST: return USUAL_LEFT_WRIST;
    case MOCAP_SEGMENT_RIGHT_WRIST: return USUAL_RIGHT_WRIST;
    case MOCAP_SEGMENT_HEAD: return USUAL_HEAD;
    default: return NULL;
    }
}

/* The longer a sensor is silent, the less what it is fed (a wrist's held sample, the head as the
 * model last posed it) says about where the bone is now: an arm raised when its sensor dropped
 * stays raised, a head the model guesses from its own guesses wanders off. So a silent wrist or
 * head moves towards its bone's usual orientation relative to the
 * pelvis' heading, reached after SILENT_SETTLE_S (15 validation clips, 5 s gap, the pose / the
 * bone / new frames past 90 deg: wrists 9.25 - 9.92 -> 9.05 - 9.25 deg, 42 - 55 -> 38 - 46 deg,
 * 318 / 702 -> 92 / 289; head 9.67 -> 9.08 deg, 43 -> 27 deg, 379 -> 6; settling in 0, 1 or 2 s,
 * halfway, or arms hanging down did less). The shins, tied to the walking body, did not gain. */
static void settle_silent_sensors(const mocap_solver *s, character *ch, const mocap_frame *f,
                                  float *orientation, const float *mask)
{
    if (!pelvis_fed(s, mask)) return;
    const float pelvis_now = bone_heading(orientation + s->pelvis_index * 9);
    for (int k = 0; k < s->sensors; ++k) {
        const float *usual_in_pelvis = usual_orientation(s->info.sensor_segments[k]);
        const mocap_sensor_frame *sf = model_sensor(ch, f, k);
        if (!usual_in_pelvis || !sf) continue;
        if (!silent_sensor_fed(sf, mask, k)) {
            ch->silent_frames[k] = 0;
            continue;
        }
        if (ch->silent_frames[k] < INT32_MAX) ch->silent_frames[k]++;
        double share = ch->silent_frames[k] * s->drift.dt / SILENT_SETTLE_S;
        if (share > 1.0) share = 1.0;
        float usual[9];
        memcpy(usual, usual_in_pelvis, sizeof usual);
        turn_about_vertical(usual, pelvis_now);
        float *m = orientation + k * 9;
        double from[4], to[4], q[4], r[9];
        if (skeleton_matrix_to_quat(m, from) != 0 || skeleton_matrix_to_quat(usual, to) != 0) continue;
        quat_slerp(q, from, to, share);
        quat_to_mat3(r, q);
        for (int i = 0; i < 9; ++i) m[i] = (float)r[i];
    }
}

/* Seconds over which a sensor that comes back eases from its stand-in to its own readings. */
#define RETURN_EASE_S 0.15

/* A stand-in is a guess, and when the sensor comes back the guess can be tens of degrees off
 * (a settled wrist, a head the model guessed): fed the reading at once, the model snaps the bone
 * round in one frame, faster than a person turns it. So the sensor is fed its own reading
 * turned by the stand-in's offset at the return, the offset fading to nothing over
 * RETURN_EASE_S: the bone follows the sensor's motion from the first frame and reaches it
 * after the ease. */
static void ease_returning_sensors(const mocap_solver *s, character *ch, const mocap_frame *f,
                                   float *orientation, const float *mask)
{
    const int32_t ease_frames = (int32_t)(RETURN_EASE_S / s->drift.dt + 0.5);
    for (int k = 0; k < s->sensors; ++k) {
        const uint32_t bit = 1u << k;
        const mocap_sensor_frame *sf = model_sensor(ch, f, k);
        float *m = orientation + k * 9;
        if (silent_sensor_fed(sf, mask, k)) {
            memcpy(ch->stand_in_rot[k], m, sizeof ch->stand_in_rot[k]);
            ch->stood_in |= bit;
            ch->returning &= ~bit;
            continue;
        }
        if (!sensor_live(sf) || (mask && mask[k] == 0.0f)) {   /* nothing, or nothing usable */
            ch->stood_in &= ~bit;
            ch->returning &= ~bit;
            continue;
        }
        double live[4];
        if (skeleton_matrix_to_quat(m, live) != 0) {
            ch->stood_in &= ~bit;
            ch->returning &= ~bit;
            continue;
        }
        if (ch->stood_in & bit) {
            double stand_in[4], live_inverse[4];
            ch->stood_in &= ~bit;
            if (skeleton_matrix_to_quat(ch->stand_in_rot[k], stand_in) != 0) continue;
            quat_conjugate(live_inverse, live);
            quat_multiply(ch->return_offset[k], stand_in, live_inverse);
            ch->returned_frames[k] = 0;
            ch->returning |= bit;
        }
        if (!(ch->returning & bit)) continue;
        if (++ch->returned_frames[k] >= ease_frames) {
            ch->returning &= ~bit;
            continue;
        }
        static const double identity[4] = {1.0, 0.0, 0.0, 0.0};
        double offset[4], q[4], r[9];
        quat_slerp(offset, identity, ch->return_offset[k],
                   1.0 - (double)ch->returned_frames[k] / (double)ease_frames);
        quat_multiply(q, offset, live);
        quat_to_mat3(r, q);
        for (int i = 0; i < 9; ++i) m[i] = (float)r[i];
    }
}

/* The spine towards the chest sensor (chest_follow.h), when the chest has a sample of its own:
 * a silent chest's stand-in is the model's own guess, and a masked one was not read. */
static void follow_chest(const mocap_solver *s, const character *ch, const mocap_frame *f,
                         const float *orientation, const float *mask, double (*q)[4])
{
    const int k = s->chest_index;
    if (s->chest_follow <= 0.0 || k < 0 || (mask && mask[k] == 0.0f)) return;
    if (!sensor_live(model_sensor(ch, f, k))) return;
    double m[9], chest[4];
    for (int i = 0; i < 9; ++i) m[i] = orientation[k * 9 + i];
    mat3_to_quat(chest, m);
    chest_follow_apply(q, chest, s->chest_follow);
}

static void build_pose(mocap_solver *s, int32_t c, const mocap_frame *f, int64_t taken_ns,
                       const float *rot, const float *vel, const float *contact,
                       const float *orientation, const float *mask)
{
    character *ch = s->chars[c];
    waiting_frame e;
    waiting_frame_of(&e, s, ch, f, taken_ns);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) skeleton_matrix_to_quat(rot + j * 9, e.q[j]);
    follow_chest(s, ch, f, orientation, mask, e.q);
    /* Before the stand-ins read the pose back, so a silent bone is never fed a broken guess. */
    if (s->pose_limit_deg > 0.0) pose_limits_apply(&ch->limits, s->pose_limit_deg, e.q, NULL);
    keep_sensor_bones(s, ch, (const double (*)[4])e.q);
    memcpy(e.vel, vel, sizeof e.vel);
    memcpy(e.contact, contact, sizeof e.contact);
    if (s->smoothing_delay > 0) {
        wait_for_neighbours(s, c, &e);
        return;
    }
    /* Before forward kinematics, so joint positions and the feet that drift correction pins
     * are those of the smoothed pose. */
    pose_filter_step(&ch->smoothing, &s->smoothing, e.q, MOCAP_JOINT_COUNT);
    emit_pose(s, c, &e, e.q, pose_stamp(ch, f, taken_ns));
}

static void reset_character_state(mocap_solver *s, int32_t c)
{
    character *ch = s->chars[c];
    emit_waiting(s, c, 1);   /* the frames before the reset keep their poses */
    size_t n = (size_t)s->L * (size_t)s->H;
    memset(ch->state_h, 0, n * sizeof(float));
    memset(ch->state_c, 0, n * sizeof(float));
    ch->drift.initialized = 0;
    pose_filter_reset(&ch->smoothing);
    pose_limits_reset(&ch->limits);
    ch->have_last_pose = 0;
    ch->have_bones = 0;
    ch->have_headings = 0;
    ch->have_pelvis_heading_at = 0;
    memset(ch->silent_frames, 0, sizeof ch->silent_frames);
    ch->stood_in = ch->returning = 0;
}

/* Keeps a failed inference's status and text (mocap_last_error on this thread) for the stats:
 * the solver thread has no caller to return them to. */
static void note_run_failure(mocap_solver *s, mocap_status status)
{
    mocap_mutex_lock(s->error_lock);
    s->last_run_status = status;
    mocap_copy_error(s->last_run_error, sizeof s->last_run_error);
    if (s->first_run_error[0] == '\0')
        snprintf(s->first_run_error, sizeof s->first_run_error, "%s", s->last_run_error);
    mocap_mutex_unlock(s->error_lock);
}

/* ---------------------------------------------------------------------------------------- */
/* One tick                                                                                    */

mocap_status solver_solve(mocap_solver *s, const int32_t *chars, const mocap_frame *const *frames,
                          const int64_t *taken_ns, int n)
{
    if (!s || (n > 0 && (!chars || !frames)) || n < 0 || n > s->count)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver_solve: bad arguments");
    if (!s->prepared) return mocap_fail(MOCAP_ERR_STATE, "solver_solve: solver not prepared");
    const int64_t t0 = mocap_monotonic_ns();
    const int L = s->L, H = s->H;
    int nb = 0;
    for (int i = 0; i < n; ++i) {
        int32_t c = chars[i];
        if (c < 0 || c >= s->count)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver_solve: character %d", (int)c);
        character *ch = s->chars[c];
        int64_t taken = taken_ns ? taken_ns[i] : t0;
        if (mocap_atomic_exchange_int(&ch->reset_requested, 0)) reset_character_state(s, c);
        if (s->config.require_calibration && !required_calibrated(s, ch, frames[i])) {
            mocap_atomic_add_u64(&ch->frames_uncalibrated, 1);
            continue;
        }
        if (solver_frame_input(frames[i], ch->slot_of, s->sensors, s->with_mask, s->in_ori[nb],
                               s->in_acc[nb], s->with_mask ? s->in_mask[nb] : NULL) != 0) {
            mocap_atomic_add_u64(&ch->frames_nonfinite, 1);
            hold_pose(s, c, frames[i], taken);
            continue;
        }
        const float *mask = s->with_mask ? s->in_mask[nb] : NULL;
        stand_in_silent_sensors(s, ch, frames[i], s->in_ori[nb], s->in_acc[nb], mask);
        turn_silent_pelvis(s, ch, frames[i], s->in_ori[nb], s->in_acc[nb]);
        turn_silent_wrists(s, ch, frames[i], s->in_ori[nb], mask);
        settle_silent_sensors(s, ch, frames[i], s->in_ori[nb], mask);
        ease_returning_sensors(s, ch, frames[i], s->in_ori[nb], mask);
        s->tick_taken[i] = taken;
        s->batch_index[nb++] = i;
    }
    if (nb == 0) return MOCAP_OK;

    /* Gather: inputs and each character's [L][H] state into the stream's [B][..] / [L][B][H]. */
    ort_stream *st = s->streams[nb - 1];
    float *ori = ort_stream_orientation(st), *acc = ort_stream_acceleration(st);
    float *mask = ort_stream_mask(st);
    float *sh = ort_stream_state_h(st), *sc = ort_stream_state_c(st);
    const size_t N = (size_t)s->sensors;
    for (int b = 0; b < nb; ++b) {
        int i = s->batch_index[b];
        character *ch = s->chars[chars[i]];
        memcpy(ori + (size_t)b * N * 9, s->in_ori[b], N * 9 * sizeof(float));
        memcpy(acc + (size_t)b * N * 3, s->in_acc[b], N * 3 * sizeof(float));
        if (mask) memcpy(mask + (size_t)b * N, s->in_mask[b], N * sizeof(float));
        for (int l = 0; l < L; ++l) {
            memcpy(sh + ((size_t)l * nb + b) * H, ch->state_h + (size_t)l * H, (size_t)H * sizeof(float));
            memcpy(sc + ((size_t)l * nb + b) * H, ch->state_c + (size_t)l * H, (size_t)H * sizeof(float));
        }
        mocap_atomic_add_u64(&ch->frames_solved, 1);
        if (s->tap)
            s->tap(s->tap_user, chars[i], frames[i], s->in_ori[b], s->in_acc[b],
                   s->with_mask ? s->in_mask[b] : NULL, s->sensors);
    }
    const int64_t r0 = mocap_monotonic_ns();
    mocap_status rs = ort_stream_run(st);
    const int64_t r1 = mocap_monotonic_ns();
    if (rs != MOCAP_OK) {
        note_run_failure(s, rs);
        /* The states were not touched (they live in the characters); hold the poses. */
        for (int b = 0; b < nb; ++b) {
            int i = s->batch_index[b];
            mocap_atomic_add_u64(&s->chars[chars[i]]->run_failures, 1);
            hold_pose(s, chars[i], frames[i], s->tick_taken[i]);
        }
        return rs;
    }

    /* Scatter: outputs -> poses; new state back to each character unless it is not finite. */
    const float *rot = ort_stream_joint_rotations(st);
    const float *vel = ort_stream_root_velocity(st);
    const float *con = ort_stream_foot_contact(st);
    sh = ort_stream_state_h(st);
    sc = ort_stream_state_c(st);
    for (int b = 0; b < nb; ++b) {
        int i = s->batch_index[b];
        character *ch = s->chars[chars[i]];
        int ok = all_finite(rot + (size_t)b * MOCAP_JOINT_COUNT * 9, MOCAP_JOINT_COUNT * 9) && all_finite(vel + (size_t)b * 3, 3) &&
                 all_finite(con + (size_t)b * 2, 2);
        for (int l = 0; ok && l < L; ++l)
            ok = all_finite(sh + ((size_t)l * nb + b) * H, (size_t)H) &&
                 all_finite(sc + ((size_t)l * nb + b) * H, (size_t)H);
        if (!ok) {
            mocap_atomic_add_u64(&ch->outputs_nonfinite, 1);
            hold_pose(s, chars[i], frames[i], s->tick_taken[i]);
            continue;
        }
        for (int l = 0; l < L; ++l) {
            memcpy(ch->state_h + (size_t)l * H, sh + ((size_t)l * nb + b) * H, (size_t)H * sizeof(float));
            memcpy(ch->state_c + (size_t)l * H, sc + ((size_t)l * nb + b) * H, (size_t)H * sizeof(float));
        }
        build_pose(s, chars[i], frames[i], s->tick_taken[i], rot + (size_t)b * MOCAP_JOINT_COUNT * 9,
                   vel + (size_t)b * 3, con + (size_t)b * 2, s->in_ori[b],
                   s->with_mask ? s->in_mask[b] : NULL);
    }
    const int64_t t1 = mocap_monotonic_ns();
    mocap_atomic_add_u64(&s->ticks, 1);
    if (nb >= 2) mocap_atomic_add_u64(&s->batched_calls, 1);
    if ((uint64_t)nb > mocap_atomic_load_u64(&s->max_batch)) mocap_atomic_store_u64(&s->max_batch, (uint64_t)nb);
    mocap_atomic_add_u64(&s->solve_ns_total, (uint64_t)(t1 - t0));
    mocap_atomic_add_u64(&s->run_ns_total, (uint64_t)(r1 - r0));
    if ((uint64_t)(t1 - t0) > mocap_atomic_load_u64(&s->solve_ns_max))
        mocap_atomic_store_u64(&s->solve_ns_max, (uint64_t)(t1 - t0));
    return MOCAP_OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Thread                                                                                      */

/* Make the character's next usable frame pending (skipping uncalibrated ones), if any. */
static void pull_frame(mocap_solver *s, character *ch, int64_t now)
{
    while (!ch->pending && !ch->session_ended) {
        if (ch->buf_pos == ch->buf_count) {
            uint32_t got = 0;
            mocap_status st = mocap_session_drain(ch->session, ch->buf, FRAME_BUFFER, &got);
            if (st == MOCAP_ERR_END_OF_STREAM) {
                ch->session_ended = 1;
                return;
            }
            if (got == 0) return;
            ch->buf_count = got;
            ch->buf_pos = 0;
            ch->buf_taken_ns = now;
        }
        const mocap_frame *f = &ch->buf[ch->buf_pos++];
        if (s->config.require_calibration && !required_calibrated(s, ch, f)) {
            mocap_atomic_add_u64(&ch->frames_uncalibrated, 1);
            continue;
        }
        ch->pending = f;
        ch->last_frame_ns = now;
    }
}

static void solver_main(void *arg)
{
    mocap_solver *s = (mocap_solver *)arg;
    int64_t first_ready_ns = 0;
    while (!mocap_atomic_load_int(&s->stop)) {
        const int64_t now = mocap_monotonic_ns();
        int awaited = 0, ready = 0, backlog = 0;
        for (int c = 0; c < s->count; ++c) {
            character *ch = s->chars[c];
            if (mocap_atomic_load_int(&ch->ended)) continue;
            /* A fast replay whose consumer is behind keeps its frames (its session waits). */
            if (ch->replay_fast && spsc_ring_size(&ch->poses) >= POSE_RING_POSES) continue;
            pull_frame(s, ch, now);
            if (!ch->pending) {
                if (ch->session_ended) {
                    emit_waiting(s, c, 1);   /* the last frames get their poses */
                    mocap_atomic_store_int(&ch->ended, 1); /* every pose was pushed before */
                    continue;
                }
                /* Waited for only while it delivers frames regularly (not unplugged/silent). */
                if (ch->last_frame_ns != 0 && now - ch->last_frame_ns < ABSENT_PERIODS * s->period_ns)
                    ++awaited;
                continue;
            }
            ++awaited;
            ++ready;
            if (ch->buf_pos < ch->buf_count) backlog = 1;
        }
        if (ready == 0) {
            first_ready_ns = 0;
            mocap_sleep_ms(1);
            continue;
        }
        if (first_ready_ns == 0) first_ready_ns = now;
        /* Stragglers: wait while some awaited character has no frame yet, up to one period,
         * unless a ready character has a backlog to catch up on. */
        if (ready < awaited && !backlog && now - first_ready_ns < s->period_ns) {
            mocap_sleep_ms(1);
            continue;
        }
        int n = 0;
        for (int c = 0; c < s->count; ++c) {
            character *ch = s->chars[c];
            if (!ch->pending) continue;
            if (ch->replay_fast && spsc_ring_size(&ch->poses) >= POSE_RING_POSES) continue;
            s->tick_chars[n] = c;
            s->tick_frames[n] = ch->pending;
            s->tick_taken[n] = ch->buf_taken_ns;
            ++n;
        }
        int64_t taken[MOCAP_MAX_CHARACTERS];
        memcpy(taken, s->tick_taken, (size_t)n * sizeof taken[0]);
        solver_solve(s, s->tick_chars, s->tick_frames, taken, n);
        for (int i = 0; i < n; ++i) s->chars[s->tick_chars[i]]->pending = NULL;
        first_ready_ns = 0;
    }
}

/* ---------------------------------------------------------------------------------------- */
/* Public API                                                                                  */

mocap_status mocap_solver_config_defaults(mocap_solver_config *c)
{
    if (!c) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver config is NULL");
    memset(c, 0, sizeof *c);
    c->struct_size = sizeof *c;
    c->contact_threshold = 0.5f;
    c->floor_height = 0.0f;
    c->drift_correction = 1;
    c->require_calibration = 1;
    c->smoothing_min_cutoff_hz = 2.0f;
    c->smoothing_beta = 12.0f;
    return MOCAP_OK;
}

mocap_status mocap_solver_open(mocap_model *model, const mocap_solver_config *config,
                               mocap_solver **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_solver_open: out is NULL");
    *out = NULL;
    if (!model) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "mocap_solver_open: model is NULL");
    mocap_solver_config cfg;
    if (config) {
        if (config->struct_size != sizeof(mocap_solver_config))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver config struct_size is %u, this "
                              "library expects %u (call mocap_solver_config_defaults)",
                              (unsigned)config->struct_size, (unsigned)sizeof(mocap_solver_config));
        cfg = *config;
    } else {
        mocap_solver_config_defaults(&cfg);
    }
    if (!(cfg.contact_threshold >= 0.0f && cfg.contact_threshold <= 1.0f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "contact_threshold %g is outside 0..1",
                          (double)cfg.contact_threshold);
    if (!isfinite(cfg.floor_height))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "floor_height is not finite");
    if (!(cfg.smoothing_min_cutoff_hz >= 0.0f && cfg.smoothing_min_cutoff_hz < 1e6f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "smoothing_min_cutoff_hz %g is not a frequency "
                          "(0 turns smoothing off)", (double)cfg.smoothing_min_cutoff_hz);
    if (!(cfg.smoothing_beta >= 0.0f && cfg.smoothing_beta < 1e6f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "smoothing_beta %g is outside 0..1e6",
                          (double)cfg.smoothing_beta);
    const mocap_model_info *info = model_info(model);
    if (!(info->frame_rate > 0.0f) || info->state_layers < 1 || info->state_size < 1)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "model info is not usable");
    mocap_solver *s = (mocap_solver *)calloc(1, sizeof *s);
    if (!s) return mocap_fail(MOCAP_ERR_NO_MEMORY, "mocap_solver_open: out of memory");
    if (mocap_mutex_create(&s->error_lock) != 0) {
        free(s);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "mocap_solver_open: could not create a mutex");
    }
    s->model = model;
    s->info = *info;
    s->config = cfg;
    mocap_status st = skeleton_init(&s->sk, info->joint_parents, (const float (*)[3])info->rest_offsets,
                                    MOCAP_JOINT_COUNT);
    if (st != MOCAP_OK) {
        mocap_mutex_destroy(s->error_lock);
        free(s);
        return st;
    }
    s->L = info->state_layers;
    s->H = info->state_size;
    s->sensors = (int)info->sensor_count;
    s->with_mask = model_has_mask(model);
    s->pelvis_index = -1;
    s->chest_index = -1;
    for (int k = 0; k < s->sensors; ++k) {
        if (info->sensor_segments[k] == MOCAP_SEGMENT_PELVIS) s->pelvis_index = k;
        if (mocap_segment_joint(info->sensor_segments[k]) == CHEST_FOLLOW_SPINE3) s->chest_index = k;
    }
    s->period_ns = (int64_t)(1e9 / info->frame_rate);
    s->drift.dt = 1.0 / info->frame_rate;
    s->smoothing.dt = 1.0 / info->frame_rate;
    s->smoothing.min_cutoff_hz = cfg.smoothing_min_cutoff_hz;
    s->smoothing.beta = cfg.smoothing_beta;
    s->smoothing.speed_cutoff_hz = 1.0;
    s->smoothing.trend_gain = POSE_FILTER_TREND_GAIN;
    s->drift.contact_threshold = cfg.contact_threshold;
    s->drift.floor_height = cfg.floor_height;
    s->drift.foot_height[0] = s->sk.foot_height[0];
    s->drift.foot_height[1] = s->sk.foot_height[1];
    s->drift.foot_lock = DRIFT_FOOT_LOCK;
    s->pin.dt = 1.0 / info->frame_rate;
    s->pin.max_offset = 0.0;   /* off until mocap_solver_set_foot_pinning */
    s->pin.release_s = FOOT_PIN_RELEASE_S;
    s->drift.enabled = cfg.drift_correction != 0;
    *out = s;
    return MOCAP_OK;
}

mocap_status mocap_solver_add_character(mocap_solver *s, mocap_session *session, int32_t *character_out)
{
    if (!s || !session) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver or session is NULL");
    if (s->started || s->prepared)
        return mocap_fail(MOCAP_ERR_STATE, "characters are added before mocap_solver_start");
    if (s->count >= MOCAP_MAX_CHARACTERS)
        return mocap_fail(MOCAP_ERR_STATE, "a solver takes at most %d characters", MOCAP_MAX_CHARACTERS);
    for (int c = 0; c < s->count; ++c)
        if (s->chars[c]->session == session)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "this session is already character %d", c);
    const mocap_session_config *sc = session_config(session);
    double rate = sc->output_rate_hz, want = s->info.frame_rate;
    if (!(fabs(rate - want) <= 1e-3 * want))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "the session's output rate is %g Hz but the "
                          "model %s expects %g Hz frames: open the session with output_rate_hz = %g",
                          rate, s->info.model_name, want, want);
    int8_t slot_of[MOCAP_MAX_SENSORS];
    for (int k = 0; k < s->sensors; ++k) {
        const int32_t seg = s->info.sensor_segments[k];
        slot_of[k] = -1;
        for (uint32_t i = 0; i < sc->sensor_count; ++i)
            if (sc->sensor_segments[i] == seg) slot_of[k] = (int8_t)i;
        if (slot_of[k] < 0 && (s->info.sensor_required_mask & (1u << k)))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "the model %s needs a sensor on the %s, "
                              "and the session has none: add it to the session's sensors",
                              s->info.model_name, mocap_segment_name(seg));
    }
    character *ch = (character *)calloc(1, sizeof *ch);
    size_t n = (size_t)s->L * (size_t)s->H;
    if (ch) {
        ch->state_h = (float *)calloc(2 * n, sizeof(float));
        if (ch->state_h) ch->state_c = ch->state_h + n;
    }
    if (!ch || !ch->state_h || spsc_ring_init(&ch->poses, sizeof(mocap_pose), POSE_RING_POSES) != 0 ||
        triple_buffer_init(&ch->newest_pose, sizeof(mocap_pose)) != 0) {
        if (ch) {
            free(ch->state_h);
            spsc_ring_destroy(&ch->poses);
            triple_buffer_destroy(&ch->newest_pose);
        }
        free(ch);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "out of memory adding a character");
    }
    ch->session = session;
    memcpy(ch->slot_of, slot_of, sizeof slot_of);
    ch->replay = sc->source_kind == MOCAP_SOURCE_REPLAY;
    ch->replay_fast = ch->replay && !sc->replay_realtime;
    mocap_atomic_store_u64(&ch->velocity_gain_bits, double_to_bits(1.0));
    s->chars[s->count] = ch;
    if (character_out) *character_out = s->count;
    s->count++;
    return MOCAP_OK;
}

mocap_status solver_prepare(mocap_solver *s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (s->prepared) return MOCAP_OK;
    if (s->count == 0) return mocap_fail(MOCAP_ERR_STATE, "the solver has no characters: add one first");
    for (int b = 1; b <= s->count; ++b) {
        mocap_status st = ort_stream_create(model_ort(s->model), b, 1, &s->streams[b - 1]);
        if (st != MOCAP_OK) {
            for (int k = 0; k < b - 1; ++k) {
                ort_stream_destroy(s->streams[k]);
                s->streams[k] = NULL;
            }
            return st;
        }
    }
    s->prepared = 1;
    return MOCAP_OK;
}

mocap_status mocap_solver_start(mocap_solver *s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (s->started) return mocap_fail(MOCAP_ERR_STATE, "solver already started");
    mocap_status st = solver_prepare(s);
    if (st != MOCAP_OK) return st;
    if (mocap_thread_start(&s->thread, solver_main, s, "mocap-solver") != 0)
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "could not start the solver thread");
    s->started = 1;
    return MOCAP_OK;
}

void mocap_solver_close(mocap_solver *s)
{
    if (!s) return;
    mocap_atomic_store_int(&s->stop, 1);
    if (s->thread) mocap_thread_join(s->thread);
    for (int b = 0; b < MOCAP_MAX_CHARACTERS; ++b) ort_stream_destroy(s->streams[b]);
    for (int c = 0; c < s->count; ++c) {
        spsc_ring_destroy(&s->chars[c]->poses);
        triple_buffer_destroy(&s->chars[c]->newest_pose);
        free(s->chars[c]->state_h);
        free(s->chars[c]);
    }
    if (s->error_lock) mocap_mutex_destroy(s->error_lock);
    free(s);
}

static mocap_status check_character(mocap_solver *s, int32_t c)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (c < 0 || c >= s->count)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "character %d does not exist (%d added)",
                          (int)c, s->count);
    return MOCAP_OK;
}

/* A pose the consumer has not been handed yet (poll and drain may both have run). */
static int pose_is_new(const character *ch, const mocap_pose *p)
{
    return !ch->have_latest || p->sequence > ch->latest.sequence;
}

static void hand_out(character *ch, const mocap_pose *p)
{
    ch->latest = *p;
    ch->have_latest = 1;
}

mocap_status mocap_solver_poll_latest(mocap_solver *s, int32_t c, mocap_pose *out)
{
    mocap_status st = check_character(s, c);
    if (st != MOCAP_OK) return st;
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "out is NULL");
    character *ch = s->chars[c];
    int ended = mocap_atomic_load_int(&ch->ended); /* before popping: see mocap_solver_drain */
    int got = 0;
    const mocap_pose *p;
    while ((p = (const mocap_pose *)spsc_ring_peek(&ch->poses)) != NULL) {
        if (pose_is_new(ch, p)) {
            hand_out(ch, p);
            got = 1;
        }
        spsc_ring_release(&ch->poses);
    }
    /* After a long pause the ring holds the oldest poses and newer ones were dropped; the
     * newest is here. Taken after the ring, so it is at least as new as what the ring held. */
    const mocap_pose *newest = (const mocap_pose *)triple_buffer_take(&ch->newest_pose);
    if (newest && pose_is_new(ch, newest)) {
        hand_out(ch, newest);
        got = 1;
    }
    if (got) {
        *out = ch->latest;
        return MOCAP_OK;
    }
    if (ended) return mocap_fail(MOCAP_ERR_END_OF_STREAM, "character %d: replay finished", (int)c);
    return MOCAP_ERR_NO_DATA;
}

mocap_status mocap_solver_drain(mocap_solver *s, int32_t c, mocap_pose *out, uint32_t capacity,
                                uint32_t *count)
{
    mocap_status st = check_character(s, c);
    if (st != MOCAP_OK) return st;
    if (!out || !count) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "out or count is NULL");
    character *ch = s->chars[c];
    /* ended is set after the last pose was pushed: read it first, so that "ended and nothing
     * popped" really means nothing is left. */
    int ended = mocap_atomic_load_int(&ch->ended);
    uint32_t n = 0;
    while (n < capacity && spsc_ring_pop(&ch->poses, &out[n]) == 0) {
        if (!pose_is_new(ch, &out[n])) continue; /* a poll already handed it out */
        hand_out(ch, &out[n]);
        ++n;
    }
    *count = n;
    if (n > 0) return MOCAP_OK;
    if (ended && capacity > 0)
        return mocap_fail(MOCAP_ERR_END_OF_STREAM, "character %d: replay finished", (int)c);
    return MOCAP_ERR_NO_DATA;
}

mocap_status mocap_solver_reset_character(mocap_solver *s, int32_t c)
{
    mocap_status st = check_character(s, c);
    if (st != MOCAP_OK) return st;
    mocap_atomic_store_int(&s->chars[c]->reset_requested, 1);
    return MOCAP_OK;
}

mocap_status mocap_solver_set_character_height(mocap_solver *s, int32_t c, float height_m)
{
    mocap_status st = check_character(s, c);
    if (st != MOCAP_OK) return st;
    double gain = 1.0;
    if (height_m != 0.0f) {
        if (!(height_m >= MOCAP_HEIGHT_MIN_M && height_m <= MOCAP_HEIGHT_MAX_M))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "height %g m is outside %g..%g m (0: the "
                              "model's own)", (double)height_m, (double)MOCAP_HEIGHT_MIN_M,
                              (double)MOCAP_HEIGHT_MAX_M);
        float training_height, exponent;
        st = mocap_model_get_stride_scaling(s->model, &training_height, &exponent);
        if (st != MOCAP_OK) return st; /* names the model and the missing metadata */
        gain = pow((double)height_m / (double)training_height, (double)exponent - 1.0);
    }
    mocap_atomic_store_u64(&s->chars[c]->velocity_gain_bits, double_to_bits(gain));
    return MOCAP_OK;
}

mocap_status mocap_solver_set_smoothing_delay(mocap_solver *s, int32_t frames)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (s->started || s->prepared)
        return mocap_fail(MOCAP_ERR_STATE, "the smoothing delay is set before mocap_solver_start");
    if (frames < 0 || frames > MOCAP_SMOOTHING_DELAY_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "smoothing delay %d frames is outside 0..%d "
                          "(0: the one-euro filter of the newest frame)", (int)frames,
                          MOCAP_SMOOTHING_DELAY_MAX);
    s->smoothing_delay = frames;
    binomial_weights(frames, s->smoothing_weights);
    return MOCAP_OK;
}

mocap_status mocap_solver_set_foot_pinning(mocap_solver *s, float slide_m_s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (s->started || s->prepared)
        return mocap_fail(MOCAP_ERR_STATE, "foot pinning is set before mocap_solver_start");
    if (!(slide_m_s >= 0.0f && slide_m_s <= MOCAP_FOOT_PIN_SLIDE_MAX))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "foot pinning slide %g m/s is outside 0..%g "
                          "(0: off)", (double)slide_m_s, (double)MOCAP_FOOT_PIN_SLIDE_MAX);
    s->pin.max_offset = slide_m_s > 0.0f ? FOOT_PIN_MAX_OFFSET_M : 0.0;
    s->pin.creep_speed = slide_m_s;
    return MOCAP_OK;
}

mocap_status mocap_solver_set_pose_limits(mocap_solver *s, float tolerance_deg)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (s->started || s->prepared)
        return mocap_fail(MOCAP_ERR_STATE, "pose limits are set before mocap_solver_start");
    if (!(tolerance_deg == 0.0f || (tolerance_deg >= MOCAP_POSE_LIMITS_MIN_DEG &&
                                    tolerance_deg <= MOCAP_POSE_LIMITS_MAX_DEG)))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "pose limits tolerance %g deg is outside "
                          "%g..%g (0: off)", (double)tolerance_deg, (double)MOCAP_POSE_LIMITS_MIN_DEG,
                          (double)MOCAP_POSE_LIMITS_MAX_DEG);
    s->pose_limit_deg = tolerance_deg;
    return MOCAP_OK;
}

mocap_status mocap_solver_set_chest_follow(mocap_solver *s, float share)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver is NULL");
    if (s->started || s->prepared)
        return mocap_fail(MOCAP_ERR_STATE, "chest following is set before mocap_solver_start");
    if (!(share >= 0.0f && share <= 1.0f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "chest following share %g is outside 0..1 "
                          "(0: off)", (double)share);
    s->chest_follow = share;
    return MOCAP_OK;
}

void solver_set_input_tap(mocap_solver *s, solver_input_tap tap, void *user)
{
    if (!s || s->started) return;
    s->tap = tap;
    s->tap_user = user;
}

mocap_status mocap_solver_get_stats(mocap_solver *s, int32_t which, mocap_solver_stats *out)
{
    if (!s || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "solver or out is NULL");
    if (which != -1) {
        mocap_status st = check_character(s, which);
        if (st != MOCAP_OK) return st;
    }
    memset(out, 0, sizeof *out);
    out->ticks = mocap_atomic_load_u64(&s->ticks);
    out->batched_calls = mocap_atomic_load_u64(&s->batched_calls);
    out->max_batch = mocap_atomic_load_u64(&s->max_batch);
    out->solve_ns_total = mocap_atomic_load_u64(&s->solve_ns_total);
    out->solve_ns_max = mocap_atomic_load_u64(&s->solve_ns_max);
    out->run_ns_total = mocap_atomic_load_u64(&s->run_ns_total);
    for (int c = 0; c < s->count; ++c) {
        if (which != -1 && c != which) continue;
        character *ch = s->chars[c];
        out->frames_solved += mocap_atomic_load_u64(&ch->frames_solved);
        out->frames_uncalibrated += mocap_atomic_load_u64(&ch->frames_uncalibrated);
        out->frames_nonfinite += mocap_atomic_load_u64(&ch->frames_nonfinite);
        out->outputs_nonfinite += mocap_atomic_load_u64(&ch->outputs_nonfinite);
        out->poses_dropped += mocap_atomic_load_u64(&ch->poses_dropped);
        out->run_failures += mocap_atomic_load_u64(&ch->run_failures);
    }
    mocap_mutex_lock(s->error_lock);
    out->last_run_status = s->last_run_status;
    memcpy(out->first_run_error, s->first_run_error, sizeof out->first_run_error);
    memcpy(out->last_run_error, s->last_run_error, sizeof out->last_run_error);
    mocap_mutex_unlock(s->error_lock);
    return MOCAP_OK;
}
