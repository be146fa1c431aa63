/* Synthetic HiPNUC gateway streams from a known body motion (see synth.h and
 * docs/synth-trajectory.md).
 *
 * Frames used here (R_ab maps vectors in frame b to frame a):
 *   A          = mocap_world_zup_to_model: Z-up "x forward, y left" -> model (Y up, Z forward).
 *   R_wm_i     = Rz(psi_i) A^T: model -> sensor i's world, psi_i = azimuth of the model forward
 *                axis in that world (NWU: -alpha, ENU: 90 deg - alpha, plus a per-sensor spread).
 *   M_i        = sensor -> bone (mounting), so R_model_sensor = R_model_bone M_i.
 *   R_ws       = R_wm_i R_model_sensor: what the sensor reports as its quaternion.
 * Random draws come from separate streams (setup, noise, faults) so that, for one seed, the
 * mounting and headings do not change when noise or fault settings do. */
#include "synth.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "capture_file.h"
#include "error.h"
#include "platform.h"
#include "hipnuc_decoder.h"
#include "mocap_math.h"

#define STREAM_SETUP 1u
#define STREAM_NOISE 2u
#define STREAM_FAULTS 3u
#define TREMOR_FADE_S 0.5  /* tremor dies out before the motion starts from an exact T-pose */
#define OMEGA_STEP_S 1e-5  /* central difference of the prelude orientations */
#define MAX_TICKS 1e10

/* Per configured sensor (config order). */
typedef struct synth_setup {
    double world_from_model[MOCAP_MAX_SENSORS][9];
    double model_from_world[MOCAP_MAX_SENSORS][9];
    double q_world_model[MOCAP_MAX_SENSORS][4];
    double sensor_to_bone[MOCAP_MAX_SENSORS][9];
    double q_bone_sensor[MOCAP_MAX_SENSORS][4];   /* quaternion of M_i */
    double q_heading[4];                          /* model <- sensor while lying X forward */
    double acc_bias[MOCAP_MAX_SENSORS][3];        /* g, sensor frame */
    double tremor_freq[MOCAP_MAX_SENSORS][3];
    double tremor_phase[MOCAP_MAX_SENSORS][3];
    double mag_world[3];                          /* uT */
} synth_setup;

static mocap_rng stream_rng(uint64_t seed, unsigned stream)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, seed ^ (0x9E3779B97F4A7C15ull * (uint64_t)stream));
    return rng;
}

static void build_setup(const synth_config *cfg, synth_setup *su)
{
    mocap_rng rng = stream_rng(cfg->seed, STREAM_SETUP);
    double a[9], at[9];
    mocap_world_zup_to_model(a);
    mat3_transpose(at, a);
    double base_deg = cfg->world_frame == MOCAP_WORLD_ENU ? 90.0 - cfg->facing_azimuth_deg
                                                          : -cfg->facing_azimuth_deg;
    memset(su, 0, sizeof *su);
    mat3_to_quat(su->q_heading, a);
    /* Sensor i always gets the i-th draws, so the default set's setup is the same whatever
     * sensors are added after it. */
    for (uint32_t i = 0; i < cfg->sensor_count && i < MOCAP_MAX_SENSORS; i++) {
        /* Every value is drawn whatever the settings, so that one setting never shifts the
         * draws of another. */
        double q[4];
        mocap_rng_rotation(&rng, q);
        double spread_u = 2.0 * mocap_rng_uniform(&rng) - 1.0;
        double bias_dir[3];
        for (int k = 0; k < 3; k++) bias_dir[k] = mocap_rng_gaussian(&rng);
        double bias_mag = mocap_rng_uniform(&rng);
        for (int k = 0; k < 3; k++) {
            su->tremor_freq[i][k] = 0.3 + 1.2 * mocap_rng_uniform(&rng);
            su->tremor_phase[i][k] = 2.0 * MOCAP_PI * mocap_rng_uniform(&rng);
        }

        if (!cfg->random_mounting) quat_identity(q);
        if (q[0] < 0.0) for (int k = 0; k < 4; k++) q[k] = -q[k];
        quat_copy(su->q_bone_sensor[i], q);
        quat_to_mat3(su->sensor_to_bone[i], q);

        double psi = (base_deg + spread_u * cfg->heading_spread_deg) * MOCAP_DEG2RAD;
        double rz[9];
        mat3_rotation_z(rz, psi);
        mat3_multiply(su->world_from_model[i], rz, at);
        mat3_transpose(su->model_from_world[i], su->world_from_model[i]);
        mat3_to_quat(su->q_world_model[i], su->world_from_model[i]);

        double n = vec3_norm(bias_dir);
        for (int k = 0; k < 3; k++)
            su->acc_bias[i][k] = n > 0.0 ? bias_dir[k] / n * bias_mag * cfg->acc_bias_g : 0.0;
    }
    /* A mid-latitude field: 20 uT north, 44 uT down. */
    su->mag_world[0] = cfg->world_frame == MOCAP_WORLD_ENU ? 0.0 : 20.0;
    su->mag_world[1] = cfg->world_frame == MOCAP_WORLD_ENU ? 20.0 : 0.0;
    su->mag_world[2] = -44.0;
}

void synth_config_defaults(synth_config *cfg)
{
    if (!cfg) return;
    memset(cfg, 0, sizeof *cfg);
    cfg->seed = 1;
    cfg->world_frame = MOCAP_WORLD_NWU;
    cfg->facing_azimuth_deg = 37.0;
    cfg->heading_spread_deg = 180.0;
    cfg->random_mounting = 1;
    cfg->rate_hz = 100.0;
    cfg->heading_s = 3.0;
    cfg->strap_s = 2.0;
    cfg->tpose_s = 3.0;
    cfg->motion_s = 1e6; /* the whole motion */
    mocap_session_config engine;
    mocap_config_defaults(&engine);
    cfg->sensor_count = engine.sensor_count;
    for (uint32_t i = 0; i < engine.sensor_count && i < MOCAP_MAX_SENSORS; i++) {
        cfg->segments[i] = engine.sensor_segments[i];
        cfg->node_ids[i] = engine.node_ids[i];
    }
    cfg->gateway_id = 1;
    cfg->imusol_layout = HIPNUC_LAYOUT_NODE_ID;
    cfg->start_receive_ns = 1000000000LL;
    cfg->start_sensor_ms = 1000;
}

double synth_session_time(const synth_config *cfg, double t)
{
    return (double)cfg->start_receive_ns / 1e9 + t;
}

void synth_setup_rotations(const synth_config *cfg, double world_to_model[MOCAP_MAX_SENSORS][9],
                           double sensor_to_bone[MOCAP_MAX_SENSORS][9])
{
    synth_setup su;
    build_setup(cfg, &su);
    for (int i = 0; i < MOCAP_MAX_SENSORS; i++) {
        if (world_to_model) memcpy(world_to_model[i], su.model_from_world[i], sizeof su.model_from_world[i]);
        if (sensor_to_bone) memcpy(sensor_to_bone[i], su.sensor_to_bone[i], sizeof su.sensor_to_bone[i]);
    }
}

static int valid_prob(double p) { return p >= 0.0 && p <= 1.0; }
static int valid_nonneg(double x) { return isfinite(x) && x >= 0.0; }

static mocap_status check_config(const synth_config *cfg)
{
    if (cfg->world_frame != MOCAP_WORLD_NWU && cfg->world_frame != MOCAP_WORLD_ENU)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: world_frame %d is neither NWU nor ENU",
                          (int)cfg->world_frame);
    if (!(isfinite(cfg->rate_hz) && cfg->rate_hz > 0.0 && cfg->rate_hz <= 10000.0))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: rate_hz %g is not in (0, 10000]",
                          cfg->rate_hz);
    if (!valid_nonneg(cfg->heading_s) || !valid_nonneg(cfg->strap_s) ||
        !valid_nonneg(cfg->tpose_s) || !valid_nonneg(cfg->motion_s))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "synth: phase lengths must be finite and >= 0 (heading %g, strap %g, "
                          "tpose %g, motion %g)",
                          cfg->heading_s, cfg->strap_s, cfg->tpose_s, cfg->motion_s);
    if ((cfg->heading_s + cfg->strap_s + cfg->tpose_s + cfg->motion_s) * cfg->rate_hz > MAX_TICKS)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: stream too long");
    if (!isfinite(cfg->facing_azimuth_deg) || !valid_nonneg(cfg->heading_spread_deg))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: bad facing azimuth or heading spread");
    if (!valid_nonneg(cfg->acc_noise_g) || !valid_nonneg(cfg->gyr_noise_dps) ||
        !valid_nonneg(cfg->quat_noise_deg) || !valid_nonneg(cfg->acc_bias_g) ||
        !valid_nonneg(cfg->still_tremor_deg))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: noise levels must be finite and >= 0");
    if (!valid_prob(cfg->node_dropout_prob) || !valid_prob(cfg->packet_dropout_prob) ||
        !valid_prob(cfg->corrupt_byte_prob))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: fault probabilities must be in [0, 1]");
    if (cfg->imusol_layout != HIPNUC_LAYOUT_AUTO && cfg->imusol_layout != HIPNUC_LAYOUT_NODE_ID)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "synth: imusol_layout %d: 0x62 blocks always carry node ids",
                          (int)cfg->imusol_layout);
    if (cfg->sensor_count < 1 || cfg->sensor_count > MOCAP_MAX_SENSORS)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: sensor_count %u is not 1..%d",
                          (unsigned)cfg->sensor_count, MOCAP_MAX_SENSORS);
    const int sensors = (int)cfg->sensor_count;
    int present = 0;
    for (int i = 0; i < sensors; i++) {
        const int seg = cfg->segments[i];
        if (!mocap_segment_name(seg))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "synth: sensor %d: segment %d is not one of the %d in the table", i,
                              seg, (int)mocap_segment_count());
        for (int j = 0; j < i; j++)
            if (cfg->segments[j] == seg)
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                                  "synth: segment %s has two sensors (%d and %d)",
                                  mocap_segment_name(seg), j, i);
        int id = cfg->node_ids[i];
        if (id == -1) continue; /* a sensor that never sends */
        if (id < 0 || id > 255)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: node id %d of %s is not 0..255",
                              id, mocap_segment_name(seg));
        for (int j = 0; j < i; j++)
            if (cfg->node_ids[j] == id)
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: node id %d used by %s and %s",
                                  id, mocap_segment_name(cfg->segments[j]), mocap_segment_name(seg));
        present++;
    }
    if (present == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: every node id is -1");
    if (cfg->silence_count > SYNTH_MAX_SILENCES)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: %u silence windows (at most %d)",
                          (unsigned)cfg->silence_count, SYNTH_MAX_SILENCES);
    for (uint32_t w = 0; w < cfg->silence_count; w++) {
        const synth_silence *sl = &cfg->silences[w];
        int configured = 0;
        for (int i = 0; i < sensors; i++) configured |= cfg->segments[i] == sl->segment;
        if (!configured)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "synth: silence window %u: segment %s has no sensor in the set",
                              (unsigned)w, mocap_segment_name(sl->segment)
                                               ? mocap_segment_name(sl->segment) : "(invalid)");
        if (!valid_nonneg(sl->start_s) || !(isfinite(sl->length_s) && sl->length_s > 0.0))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "synth: silence window %u of %s: start %g s must be >= 0 and "
                              "length %g s > 0",
                              (unsigned)w, mocap_segment_name(sl->segment), sl->start_s,
                              sl->length_s);
    }
    return MOCAP_OK;
}

/* Sensors (bit i: config order) inside a silence window at this motion time. Windows are
 * half-open, [start, start + length), with a hair of slack so that a tick landing on a window
 * edge is not decided by the rounding of k / rate. */
static uint32_t silent_sensors(const synth_config *cfg, double motion_t)
{
    const double slack = 1e-9;
    uint32_t mask = 0;
    for (uint32_t w = 0; w < cfg->silence_count; w++) {
        const synth_silence *sl = &cfg->silences[w];
        if (motion_t < sl->start_s - slack || motion_t >= sl->start_s + sl->length_s - slack)
            continue;
        for (uint32_t i = 0; i < cfg->sensor_count; i++)
            if (cfg->segments[i] == sl->segment) mask |= 1u << i;
    }
    return mask;
}

/* The motion moves every segment that has a sensor: checked on its first pose, before anything
 * is generated or written. */
static mocap_status check_motion_segments(const synth_config *cfg, synth_motion_fn motion,
                                          void *motion_user)
{
    synth_pose first;
    memset(&first, 0, sizeof first);
    if (motion(motion_user, 0.0, &first) != 0) return MOCAP_OK; /* an empty motion: prelude only */
    for (uint32_t i = 0; i < cfg->sensor_count; i++)
        if (!(first.segment_mask & (1u << cfg->segments[i])))
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "synth: the motion does not move segment %s, which has a sensor",
                              mocap_segment_name(cfg->segments[i]));
    return MOCAP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Prelude (heading, strapping, T-pose)                                                        */
/* ------------------------------------------------------------------------------------------ */
static double smoothstep5(double u)
{
    if (u <= 0.0) return 0.0;
    if (u >= 1.0) return 1.0;
    return u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
}

/* Small sway the user cannot avoid when holding still, as a rotation in the model frame. */
static void tremor(const synth_config *cfg, const synth_setup *su, int i, double t, double q[4])
{
    double amp = cfg->still_tremor_deg * MOCAP_DEG2RAD;
    double end = cfg->heading_s + cfg->strap_s + cfg->tpose_s;
    double fade = smoothstep5((end - t) / TREMOR_FADE_S);
    double v[3];
    for (int k = 0; k < 3; k++)
        v[k] = amp * fade * sin(2.0 * MOCAP_PI * su->tremor_freq[i][k] * t + su->tremor_phase[i][k]);
    double angle = vec3_norm(v);
    if (angle <= 0.0) { quat_identity(q); return; }
    double axis[3] = {v[0] / angle, v[1] / angle, v[2] / angle};
    quat_from_axis_angle(q, axis, angle);
}

/* Orientation (model <- sensor) of sensor i during the prelude, and the bone truth. */
static void prelude_orientation(const synth_config *cfg, const synth_setup *su, int i, double t,
                                double q_model_sensor[4], double q_bone[4])
{
    double tr[4], held[4];
    tremor(cfg, su, i, t, tr);
    double strap_start = cfg->heading_s, tpose_start = cfg->heading_s + cfg->strap_s;
    if (t < strap_start) {
        quat_copy(held, su->q_heading);
    } else if (t < tpose_start) {
        quat_slerp(held, su->q_heading, su->q_bone_sensor[i],
                   smoothstep5((t - strap_start) / cfg->strap_s));
    } else {
        quat_copy(held, su->q_bone_sensor[i]);
    }
    quat_multiply(q_model_sensor, tr, held);
    if (t >= tpose_start) quat_copy(q_bone, tr);
    else quat_identity(q_bone);
}

static void rotvec_of(double out[3], const double q[4])
{
    double w = q[0], v[3] = {q[1], q[2], q[3]};
    if (w < 0.0) { w = -w; v[0] = -v[0]; v[1] = -v[1]; v[2] = -v[2]; }
    double s = vec3_norm(v);
    double k = s < 1e-15 ? 2.0 : 2.0 * atan2(s, w) / s;
    for (int j = 0; j < 3; j++) out[j] = v[j] * k;
}

static void prelude_omega(const synth_config *cfg, const synth_setup *su, int i, double t,
                          double omega[3])
{
    double qa[4], qb[4], dummy[4], qac[4], d[4];
    prelude_orientation(cfg, su, i, t - OMEGA_STEP_S, qa, dummy);
    prelude_orientation(cfg, su, i, t + OMEGA_STEP_S, qb, dummy);
    quat_conjugate(qac, qa);
    quat_multiply(d, qb, qac);
    rotvec_of(omega, d);
    for (int k = 0; k < 3; k++) omega[k] /= 2.0 * OMEGA_STEP_S;
}

/* ------------------------------------------------------------------------------------------ */
/* Raw sample of one sensor                                                                    */
/* ------------------------------------------------------------------------------------------ */
static void make_sample(const synth_config *cfg, const synth_setup *su, mocap_rng *noise, int i,
                        const double q_model_sensor[4], const double omega_model[3],
                        const double accel_model[3], uint32_t time_ms, hipnuc_sample *s)
{
    double q_ws[4], r_ws[9], r_ms[9];
    quat_multiply(q_ws, su->q_world_model[i], q_model_sensor);
    quat_normalize(q_ws);
    quat_to_mat3(r_ws, q_ws);
    quat_to_mat3(r_ms, q_model_sensor);

    double f_world[3], a_world[3], f_sensor[3], w_sensor[3], m_sensor[3];
    mat3_apply(a_world, su->world_from_model[i], accel_model);
    f_world[0] = a_world[0];
    f_world[1] = a_world[1];
    f_world[2] = a_world[2] + MOCAP_STANDARD_GRAVITY; /* specific force: a - g, g pointing down */
    double r_ws_t[9], r_ms_t[9];
    mat3_transpose(r_ws_t, r_ws);
    mat3_transpose(r_ms_t, r_ms);
    mat3_apply(f_sensor, r_ws_t, f_world);
    mat3_apply(w_sensor, r_ms_t, omega_model);
    mat3_apply(m_sensor, r_ws_t, su->mag_world);

    double q_out[4];
    quat_copy(q_out, q_ws);
    if (cfg->quat_noise_deg > 0.0) {
        double axis[3] = {mocap_rng_gaussian(noise), mocap_rng_gaussian(noise),
                          mocap_rng_gaussian(noise)};
        double angle = cfg->quat_noise_deg * MOCAP_DEG2RAD * mocap_rng_gaussian(noise);
        double n = vec3_norm(axis), qn[4];
        if (n > 0.0) {
            for (int k = 0; k < 3; k++) axis[k] /= n;
            quat_from_axis_angle(qn, axis, angle);
            quat_multiply(q_out, q_ws, qn);
            quat_normalize(q_out);
        }
    }
    if (q_out[0] < 0.0) for (int k = 0; k < 4; k++) q_out[k] = -q_out[k];

    memset(s, 0, sizeof *s);
    s->fields = HIPNUC_FIELD_NODE_ID | HIPNUC_FIELD_TIME | HIPNUC_FIELD_ACC | HIPNUC_FIELD_GYR |
                HIPNUC_FIELD_MAG | HIPNUC_FIELD_EULER | HIPNUC_FIELD_QUAT;
    s->node_id = (uint32_t)cfg->node_ids[i];
    s->time_ms = time_ms;
    s->source_tag = HIPNUC_TAG_GWSOL;
    for (int k = 0; k < 3; k++) {
        double acc = f_sensor[k] / MOCAP_STANDARD_GRAVITY + su->acc_bias[i][k];
        if (cfg->acc_noise_g > 0.0) acc += cfg->acc_noise_g * mocap_rng_gaussian(noise);
        double gyr = w_sensor[k] * MOCAP_RAD2DEG;
        if (cfg->gyr_noise_dps > 0.0) gyr += cfg->gyr_noise_dps * mocap_rng_gaussian(noise);
        s->acc_g[k] = (float)acc;
        s->gyr_dps[k] = (float)gyr;
        s->mag_ut[k] = (float)m_sensor[k];
    }
    for (int k = 0; k < 4; k++) s->quat[k] = (float)q_out[k];
    /* HiPNUC Euler angles of the reported quaternion: R = Rz(yaw) Ry(pitch) Rx(roll). */
    double r[9];
    quat_to_mat3(r, q_out);
    double sp = -r[6];
    if (sp > 1.0) sp = 1.0;
    if (sp < -1.0) sp = -1.0;
    s->euler_deg[0] = (float)(atan2(r[7], r[8]) * MOCAP_RAD2DEG);
    s->euler_deg[1] = (float)(asin(sp) * MOCAP_RAD2DEG);
    s->euler_deg[2] = (float)(atan2(r[3], r[0]) * MOCAP_RAD2DEG);
}

/* ------------------------------------------------------------------------------------------ */
/* The stream                                                                                  */
/* ------------------------------------------------------------------------------------------ */
mocap_status synth_generate(const synth_config *cfg, synth_motion_fn motion, void *motion_user,
                            synth_packet_fn on_packet, void *user)
{
    if (!cfg || !on_packet)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth_generate: config or callback is NULL");
    mocap_status st = check_config(cfg);
    if (st != MOCAP_OK) return st;
    if (!motion) {
        motion = synth_builtin_motion("mixed");
        motion_user = NULL;
    }
    st = check_motion_segments(cfg, motion, motion_user);
    if (st != MOCAP_OK) return st;

    synth_setup su;
    build_setup(cfg, &su);
    mocap_rng noise = stream_rng(cfg->seed, STREAM_NOISE);
    mocap_rng faults = stream_rng(cfg->seed, STREAM_FAULTS);

    const double prelude = cfg->heading_s + cfg->strap_s + cfg->tpose_s;
    const double total = prelude + cfg->motion_s;
    /* Ticks at k / rate for every k with k / rate <= total (a hair of slack for rounding). */
    const uint64_t ticks = (uint64_t)floor(total * cfg->rate_hz + 1e-9) + 1;

    const int sensors = (int)cfg->sensor_count;
    uint32_t configured_segments = 0;
    for (int i = 0; i < sensors; i++) configured_segments |= 1u << cfg->segments[i];
    hipnuc_sample samples[MOCAP_MAX_SENSORS];
    uint8_t payload[HIPNUC_MAX_PAYLOAD];
    uint8_t frame[HIPNUC_HEADER_SIZE + HIPNUC_MAX_PAYLOAD];
    size_t offset = 0;

    for (uint64_t k = 0; k < ticks; k++) {
        const double t = (double)k / cfg->rate_hz;
        synth_pose truth;
        synth_packet_info info;
        memset(&info, 0, sizeof info);
        info.index = k;
        info.t = t;
        info.receive_ns = cfg->start_receive_ns + (int64_t)llround(t * 1e9);
        info.phase = t < cfg->heading_s ? 0 : t < cfg->heading_s + cfg->strap_s ? 1
                     : t < prelude ? 2 : 3;
        const uint32_t time_ms = cfg->start_sensor_ms + (uint32_t)(uint64_t)llround(t * 1000.0);

        if (info.phase == 3) {
            memset(&truth, 0, sizeof truth);
            if (motion(motion_user, t - prelude, &truth) != 0) break; /* the motion has ended */
            const uint32_t missing = configured_segments & ~truth.segment_mask;
            if (missing) {
                int seg = 0;
                while (!(missing & (1u << seg))) seg++;
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                                  "synth: the motion does not move segment %s, which has a sensor",
                                  mocap_segment_name(seg));
            }
        } else {
            /* The prelude's truth: every bone in the T-pose, the sensors' own sway added below. */
            memset(&truth, 0, sizeof truth);
            for (int seg = 0; seg < MOCAP_MAX_SENSORS; seg++) quat_identity(truth.bone_quat[seg]);
            truth.segment_mask = (1u << mocap_segment_count()) - 1u;
        }
        for (int i = 0; i < sensors; i++) {
            const int seg = cfg->segments[i];
            double q_ms[4], omega[3], accel[3] = {0.0, 0.0, 0.0};
            if (info.phase == 3) {
                quat_multiply(q_ms, truth.bone_quat[seg], su.q_bone_sensor[i]);
                quat_normalize(q_ms);
                for (int k3 = 0; k3 < 3; k3++) {
                    omega[k3] = truth.angular_velocity[seg][k3];
                    accel[k3] = truth.accel[seg][k3];
                }
            } else {
                double q_bone[4];
                prelude_orientation(cfg, &su, i, t, q_ms, q_bone);
                prelude_omega(cfg, &su, i, t, omega);
                quat_copy(truth.bone_quat[seg], q_bone);
                for (int k3 = 0; k3 < 3; k3++) {
                    truth.accel[seg][k3] = 0.0;
                    truth.angular_velocity[seg][k3] = info.phase == 2 ? omega[k3] : 0.0;
                }
            }
            make_sample(cfg, &su, &noise, i, q_ms, omega, accel, time_ms, &samples[i]);
        }

        /* The packet and node draws happen on every tick, dropped or not, so that one packet's
         * fate does not shift which nodes the next ones lose. */
        int drop_packet = cfg->packet_dropout_prob > 0.0 &&
                          mocap_rng_uniform(&faults) < cfg->packet_dropout_prob;
        hipnuc_sample present[MOCAP_MAX_SENSORS];
        uint32_t n = 0;
        info.silent_mask = info.phase == 3 ? silent_sensors(cfg, t - prelude) : 0u;
        for (int i = 0; i < sensors; i++) {
            int drop_node = cfg->node_dropout_prob > 0.0 &&
                            mocap_rng_uniform(&faults) < cfg->node_dropout_prob;
            if (cfg->node_ids[i] < 0 || drop_node || (info.silent_mask & (1u << i))) continue;
            present[n++] = samples[i];
            info.node_mask |= 1u << i;
        }
        info.offset = offset;
        if (drop_packet || n == 0) {
            /* A gateway with nothing to report sends nothing. */
            info.dropped = 1;
            info.intact = 1;
            info.node_mask = 0;
            if (on_packet(user, &info, NULL, &truth) != 0) break;
            continue;
        }
        size_t plen = hipnuc_encode_gwsol(cfg->gateway_id, present, n, payload, sizeof payload);
        size_t flen = plen ? hipnuc_encode_frame(payload, plen, frame, sizeof frame) : 0;
        if (flen == 0)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth: could not encode packet %llu",
                              (unsigned long long)k);
        info.intact = 1;
        if (cfg->corrupt_byte_prob > 0.0) {
            for (size_t b = 0; b < flen; b++) {
                if (mocap_rng_uniform(&faults) < cfg->corrupt_byte_prob) {
                    /* A different value, uniform over the other 255. */
                    frame[b] = (uint8_t)(frame[b] + 1 + mocap_rng_next(&faults) % 255u);
                    info.intact = 0;
                }
            }
        }
        info.length = flen;
        offset += flen;
        if (on_packet(user, &info, frame, &truth) != 0) break;
    }
    return MOCAP_OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Capture file + truth CSV                                                                    */
/* ------------------------------------------------------------------------------------------ */
typedef struct write_ctx {
    const synth_config *cfg;
    capture_writer *writer;
    FILE *truth;
    const char *capture_path;
    const char *truth_path;
    mocap_status status;
} write_ctx;

static int write_packet(void *user, const synth_packet_info *info, const uint8_t *bytes,
                        const synth_pose *truth)
{
    write_ctx *ctx = user;
    if (!info->dropped) {
        mocap_status st = capture_writer_append(ctx->writer, info->receive_ns, bytes, info->length);
        if (st == MOCAP_OK) st = capture_writer_poll(ctx->writer, info->receive_ns);
        if (st != MOCAP_OK) { ctx->status = st; return 1; }
    }
    if (ctx->truth) {
        int bad = fprintf(ctx->truth, "%.9f,%d", synth_session_time(ctx->cfg, info->t),
                          (int)info->phase) < 0;
        for (uint32_t i = 0; i < ctx->cfg->sensor_count && !bad; i++) {
            const int seg = ctx->cfg->segments[i];
            const double *q = truth->bone_quat[seg], *a = truth->accel[seg];
            bad = fprintf(ctx->truth, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g", q[0], q[1], q[2], q[3],
                          a[0], a[1], a[2]) < 0;
        }
        if (!bad) bad = fputc('\n', ctx->truth) == EOF;
        if (bad) {
            char buf[128];
            ctx->status = mocap_fail(MOCAP_ERR_IO, "truth file %s: %s", ctx->truth_path,
                                     mocap_errno_text(errno, buf, sizeof buf));
            return 1;
        }
    }
    return 0;
}

mocap_status synth_write_capture(const synth_config *cfg, synth_motion_fn motion,
                                 void *motion_user, const char *capture_path,
                                 const char *truth_path)
{
    if (!cfg || !capture_path || !capture_path[0])
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "synth_write_capture: config or path missing");
    mocap_status st = check_config(cfg);
    if (st == MOCAP_OK)
        st = check_motion_segments(cfg, motion ? motion : synth_builtin_motion("mixed"),
                                   motion ? motion_user : NULL);
    if (st != MOCAP_OK) return st;

    write_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.cfg = cfg;
    ctx.capture_path = capture_path;
    ctx.truth_path = truth_path;
    if (truth_path && truth_path[0]) {
        ctx.truth = mocap_fopen(truth_path, "w");
        if (!ctx.truth) {
            int e = errno;
            char buf[128];
            return mocap_fail(e == ENOENT ? MOCAP_ERR_NOT_FOUND
                              : (e == EACCES || e == EPERM) ? MOCAP_ERR_PERMISSION : MOCAP_ERR_IO,
                              "truth file %s: %s", truth_path, mocap_errno_text(e, buf, sizeof buf));
        }
        int bad = fputs("t_session,phase", ctx.truth) == EOF;
        for (uint32_t i = 0; i < cfg->sensor_count && !bad; i++) {
            const char *n = mocap_segment_name(cfg->segments[i]);
            bad = fprintf(ctx.truth, ",%s_qw,%s_qx,%s_qy,%s_qz,%s_ax,%s_ay,%s_az", n, n, n, n, n, n,
                          n) < 0;
        }
        if (!bad) bad = fputc('\n', ctx.truth) == EOF;
        if (bad) {
            fclose(ctx.truth);
            return mocap_fail(MOCAP_ERR_IO, "truth file %s: write failed", truth_path);
        }
    }
    st = capture_writer_open(capture_path, &ctx.writer);
    if (st != MOCAP_OK) {
        if (ctx.truth) fclose(ctx.truth);
        return st;
    }
    st = synth_generate(cfg, motion, motion_user, write_packet, &ctx);
    if (st == MOCAP_OK) st = ctx.status;
    /* The first failure is the one reported: closing after it must not replace its text. */
    char first_error[256] = "";
    if (st != MOCAP_OK) mocap_copy_error(first_error, sizeof first_error);
    mocap_status close_st = capture_writer_close(ctx.writer);
    if (st == MOCAP_OK) st = close_st;
    if (ctx.truth) {
        int bad = fflush(ctx.truth) != 0 || ferror(ctx.truth);
        bad |= fclose(ctx.truth) != 0;
        if (bad && st == MOCAP_OK)
            st = mocap_fail(MOCAP_ERR_IO, "truth file %s: write failed (disk full?)", truth_path);
    }
    if (first_error[0] != '\0') return mocap_fail(st, "%s", first_error);
    return st;
}
