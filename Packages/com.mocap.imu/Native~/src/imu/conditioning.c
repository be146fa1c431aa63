/* Signal conditioning: device units to SI, quaternion validation, timestamp unwrapping and the
 * sensor-clock to receive-clock mapping. */
#include "conditioning.h"

#include <math.h>
#include <string.h>

#include "mocap_math.h"

#define MS_PER_DAY 86400000LL
#define U32_SPAN 4294967296LL
/* A backwards step is taken for a wrap only when the clock, continued across that wrap, lands
 * at most this far after the previous sample: a dropout of up to 10 minutes across the wrap is
 * still unwrapped, while a reboot from mid-day (a large backwards step that is not "nearly a
 * whole day") is not mistaken for one. Anything misjudged here shows up as a clock jump, which
 * clock_map handles by re-initialising. */
#define UNWRAP_MAX_GAP_MS 600000LL

#define CLOCK_DEFAULT_RESET_AFTER_S 1.0
/* 1e-3 s/s follows a sensor crystal up to 1000 ppm slow, far beyond real parts (~20-100 ppm),
 * and lets a too-low offset (one abnormally fast delivery) creep back up by only 1 ms per
 * second, which is well below a frame period. */
#define CLOCK_DEFAULT_DRIFT_PER_S 1e-3

static int all_finite(const float *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

static int all_within(const float *v, int n, double limit)
{
    for (int i = 0; i < n; i++)
        if (!(fabs((double)v[i]) <= limit))
            return 0;
    return 1;
}

int condition_sample(const hipnuc_sample *in, imu_sample *out)
{
    const int has_quat = (in->fields & HIPNUC_FIELD_QUAT) != 0;
    const int has_euler = (in->fields & HIPNUC_FIELD_EULER) != 0;
    const int has_acc = (in->fields & HIPNUC_FIELD_ACC) != 0;
    const int has_gyr = (in->fields & HIPNUC_FIELD_GYR) != 0;

    if ((has_acc && !all_finite(in->acc_g, 3)) || (has_gyr && !all_finite(in->gyr_dps, 3)))
        return CONDITION_NOT_FINITE;
    if (has_quat && !all_finite(in->quat, 4))
        return CONDITION_NOT_FINITE;
    if (!has_quat && has_euler && !all_finite(in->euler_deg, 3))
        return CONDITION_NOT_FINITE;
    if (!has_quat && !has_euler)
        return CONDITION_NO_ORIENTATION;
    if ((has_acc && !all_within(in->acc_g, 3, CONDITION_MAX_ACC_G)) ||
        (has_gyr && !all_within(in->gyr_dps, 3, CONDITION_MAX_GYR_DPS)) ||
        (!has_quat && !all_within(in->euler_deg, 3, CONDITION_MAX_EULER_DEG)))
        return CONDITION_OUT_OF_RANGE;

    double q[4];
    if (has_quat) {
        for (int i = 0; i < 4; i++)
            q[i] = (double)in->quat[i];
        /* Firmware sends an all-zero quaternion before its fusion has converged. */
        if (q[0] == 0.0 && q[1] == 0.0 && q[2] == 0.0 && q[3] == 0.0)
            return CONDITION_ZERO_QUATERNION;
        double n = quat_norm(q);
        if (fabs(n - 1.0) > CONDITION_QUAT_NORM_TOLERANCE)
            return CONDITION_NON_UNIT_QUATERNION;
        quat_normalize(q);
    } else {
        quat_from_euler_zyx(q, in->euler_deg[0] * MOCAP_DEG2RAD, in->euler_deg[1] * MOCAP_DEG2RAD,
                            in->euler_deg[2] * MOCAP_DEG2RAD);
    }

    out->node_id = in->node_id;
    memcpy(out->quat, q, sizeof q);
    for (int i = 0; i < 3; i++) {
        out->acc[i] = has_acc ? (double)in->acc_g[i] * MOCAP_STANDARD_GRAVITY : 0.0;
        out->gyr[i] = has_gyr ? (double)in->gyr_dps[i] * MOCAP_DEG2RAD : 0.0;
    }
    return CONDITION_OK;
}

void time_unwrapper_init(time_unwrapper *u)
{
    memset(u, 0, sizeof *u);
}

int64_t time_unwrap_ms(time_unwrapper *u, uint32_t raw_ms)
{
    if (!u->initialised) {
        u->initialised = 1;
        u->last_raw = raw_ms;
        u->offset_ms = 0;
        return (int64_t)raw_ms;
    }
    int64_t raw = (int64_t)raw_ms;
    int64_t last = (int64_t)u->last_raw;
    if (raw < last) {
        int64_t across_day = raw + MS_PER_DAY - last;
        int64_t across_u32 = raw + U32_SPAN - last;
        if (last < MS_PER_DAY && raw < MS_PER_DAY && across_day >= 0 &&
            across_day <= UNWRAP_MAX_GAP_MS)
            u->offset_ms += MS_PER_DAY;
        else if (across_u32 <= UNWRAP_MAX_GAP_MS)
            u->offset_ms += U32_SPAN;
        /* Otherwise a genuine backwards step (late packet, reboot): returned as is; the
         * assembler drops out-of-order samples and clock_map re-initialises after a reboot. */
    }
    u->last_raw = raw_ms;
    return raw + u->offset_ms;
}

void clock_mapper_init(clock_mapper *c)
{
    memset(c, 0, sizeof *c);
    c->reset_after_s = CLOCK_DEFAULT_RESET_AFTER_S;
    c->drift_per_s = CLOCK_DEFAULT_DRIFT_PER_S;
}

double clock_map(clock_mapper *c, double sensor_s, double receive_s)
{
    double candidate = receive_s - sensor_s; /* true offset plus this sample's latency */
    if (!c->initialised || !isfinite(c->offset) ||
        fabs(candidate - c->offset) > c->reset_after_s) {
        c->initialised = 1;
        c->offset = candidate;
        c->last_receive = receive_s;
        c->last_sensor = sensor_s;
        c->last_mapped = sensor_s + c->offset;
        return c->last_mapped;
    }
    double elapsed = receive_s - c->last_receive;
    if (elapsed < 0.0)
        elapsed = 0.0;
    /* The minimum latency is the best estimate of the offset, but a slow sensor clock makes the
     * true offset rise; letting the estimate rise slowly (and never above this sample's own
     * candidate) follows that without letting latency jitter through. */
    double raised = c->offset + c->drift_per_s * elapsed;
    c->offset = candidate < raised ? candidate : raised;
    if (receive_s > c->last_receive)
        c->last_receive = receive_s;
    double mapped = sensor_s + c->offset;
    if (sensor_s > c->last_sensor) {
        /* Newer on the sensor clock: keep it newer on ours (see CLOCK_ORDER_STEP_S). An equal or
         * older sensor time (a repeated or reordered sample) is left for the caller to refuse. */
        if (mapped < c->last_mapped + CLOCK_ORDER_STEP_S)
            mapped = c->last_mapped + CLOCK_ORDER_STEP_S;
        c->last_sensor = sensor_s;
        c->last_mapped = mapped;
    }
    return mapped;
}
