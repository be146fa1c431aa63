#include "pose_filter.h"

#include <math.h>
#include <string.h>

#include "mocap_math.h"

void pose_filter_reset(pose_filter_state *s)
{
    memset(s, 0, sizeof *s);
}

static double smoothing_factor(double cutoff_hz, double dt)
{
    double r = 2.0 * MOCAP_PI * cutoff_hz * dt;
    return r / (r + 1.0);
}

/* The rotation vector (axis times angle, rad) of a unit quaternion, the short way round. */
static void quat_to_rotation_vector(double out[3], const double q[4])
{
    double w = q[0] < 0.0 ? -q[0] : q[0];
    double sign = q[0] < 0.0 ? -1.0 : 1.0;
    double n = sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double scale = n > 1e-12 ? 2.0 * atan2(n, w) / n : 2.0;
    for (int k = 0; k < 3; ++k) out[k] = sign * q[k + 1] * scale;
}

void pose_filter_step(pose_filter_state *s, const pose_filter_params *p, double q[][4], int n)
{
    if (n > POSE_FILTER_MAX_JOINTS) n = POSE_FILTER_MAX_JOINTS;
    if (!(p->min_cutoff_hz > 0.0) || !(p->dt > 0.0)) return;
    if (!s->initialized) {
        for (int j = 0; j < n; ++j) {
            quat_copy(s->q[j], q[j]);
            s->speed[j] = 0.0;
            s->velocity[j][0] = s->velocity[j][1] = s->velocity[j][2] = 0.0;
        }
        s->initialized = 1;
        return;
    }
    const double a_speed = smoothing_factor(p->speed_cutoff_hz > 0.0 ? p->speed_cutoff_hz : 1.0, p->dt);
    const double trend = p->trend_gain > 0.0 ? (p->trend_gain < 1.0 ? p->trend_gain : 1.0) : 0.0;
    for (int j = 0; j < n; ++j) {
        /* Where the joint would be if it kept turning as it has: the base the new rotation is
         * blended into (the last filtered rotation itself without a trend). */
        double predicted[4];
        if (trend > 0.0) {
            double step[3], turn[4];
            for (int k = 0; k < 3; ++k) step[k] = s->velocity[j][k] * p->dt;
            quat_from_axis_angle(turn, step, vec3_norm(step));   /* identity for no turn */
            quat_multiply(predicted, turn, s->q[j]);
            quat_normalize(predicted);
        } else {
            quat_copy(predicted, s->q[j]);
        }
        /* Angle between the new rotation and that base: the raw speed estimate. */
        double raw_speed = quat_angle_deg(predicted, q[j]) * MOCAP_DEG2RAD / p->dt;
        s->speed[j] += a_speed * (raw_speed - s->speed[j]);
        double cutoff = p->min_cutoff_hz + (p->beta > 0.0 ? p->beta : 0.0) * s->speed[j];
        double out[4];
        quat_slerp(out, predicted, q[j], smoothing_factor(cutoff, p->dt));   /* unit length */
        if (trend > 0.0) {
            double back[4], made[4], rate[3];
            quat_conjugate(back, s->q[j]);
            quat_multiply(made, out, back);
            quat_to_rotation_vector(rate, made);
            for (int k = 0; k < 3; ++k)
                s->velocity[j][k] += trend * (rate[k] / p->dt - s->velocity[j][k]);
        }
        quat_copy(s->q[j], out);
        /* Same rotation, but on the caller's hemisphere, as unfiltered output is. */
        quat_align_hemisphere(out, q[j]);
        quat_copy(q[j], out);
    }
}
