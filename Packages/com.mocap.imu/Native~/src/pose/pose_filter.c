#include "pose_filter.h"

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

void pose_filter_step(pose_filter_state *s, const pose_filter_params *p, double q[][4], int n)
{
    if (n > POSE_FILTER_MAX_JOINTS) n = POSE_FILTER_MAX_JOINTS;
    if (!(p->min_cutoff_hz > 0.0) || !(p->dt > 0.0)) return;
    if (!s->initialized) {
        for (int j = 0; j < n; ++j) {
            quat_copy(s->q[j], q[j]);
            s->speed[j] = 0.0;
        }
        s->initialized = 1;
        return;
    }
    const double a_speed = smoothing_factor(p->speed_cutoff_hz > 0.0 ? p->speed_cutoff_hz : 1.0, p->dt);
    for (int j = 0; j < n; ++j) {
        /* Angle between the new rotation and the last filtered one: the raw speed estimate. */
        double raw_speed = quat_angle_deg(s->q[j], q[j]) * MOCAP_DEG2RAD / p->dt;
        s->speed[j] += a_speed * (raw_speed - s->speed[j]);
        double cutoff = p->min_cutoff_hz + (p->beta > 0.0 ? p->beta : 0.0) * s->speed[j];
        double out[4];
        quat_slerp(out, s->q[j], q[j], smoothing_factor(cutoff, p->dt));   /* unit length */
        quat_copy(s->q[j], out);
        /* Same rotation, but on the caller's hemisphere, as unfiltered output is. */
        quat_align_hemisphere(out, q[j]);
        quat_copy(q[j], out);
    }
}
