#include "pose_limits.h"

#include <math.h>
#include <string.h>

#include "pose_range_table.h"

#define DEG_PER_RAD 57.29577951308232

void pose_limits_reset(pose_limits_state *s)
{
    memset(s, 0, sizeof *s);
}

/* Point k of a joint's span as a unit quaternion (the int8 components are normalised again). */
static void range_point(const pose_range_span *span, uint32_t k, double p[4])
{
    const int8_t *v = pose_range_points[span->first + k];
    double n = 0.0;
    for (int i = 0; i < 4; ++i) {
        p[i] = (double)v[i];
        n += p[i] * p[i];
    }
    n = 1.0 / sqrt(n);
    for (int i = 0; i < 4; ++i) p[i] *= n;
}

static double dot4(const double a[4], const double b[4])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
}

/* The point of the span nearest q (largest |q . p| / |p|, q and -q being one rotation), as an
 * offset in the span and, in p, a unit quaternion. The points are compared by cross-multiplying
 * squares (|p|^2 is an exact integer), so the scan needs no square root or division per point. */
static uint32_t nearest_point(const pose_range_span *span, const double q[4], double p[4])
{
    uint32_t best = 0;
    double best_dot2 = -1.0, best_norm2 = 1.0;
    for (uint32_t k = 0; k < span->count; ++k) {
        const int8_t *v = pose_range_points[span->first + k];
        const double d = q[0] * v[0] + q[1] * v[1] + q[2] * v[2] + q[3] * v[3];
        const double n2 = (double)(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        if (d * d * best_norm2 > best_dot2 * n2) {
            best_dot2 = d * d;
            best_norm2 = n2;
            best = k;
        }
    }
    range_point(span, best, p);
    return best;
}

static double rotation_deg(double abs_dot)
{
    return 2.0 * acos(abs_dot > 1.0 ? 1.0 : abs_dot) * DEG_PER_RAD;
}

double pose_limits_distance_deg(int joint, const double q[4])
{
    if (joint < 0 || joint >= POSE_RANGE_JOINTS || pose_range_joints[joint].count == 0) return -1.0;
    double u[4], p[4], n = sqrt(dot4(q, q));
    for (int i = 0; i < 4; ++i) u[i] = q[i] / n;
    nearest_point(&pose_range_joints[joint], u, p);
    return rotation_deg(fabs(dot4(u, p)));
}

int pose_limits_apply(pose_limits_state *s, double tolerance_deg, double (*q)[4], uint8_t *moved)
{
    /* |q . p| above this: within the tolerance of p (the rotation angle is twice the angle
     * between the 4-vectors). */
    const double half = 0.5 * tolerance_deg / DEG_PER_RAD;
    /* A joint left at the tolerance stays put when guarded again, rounding notwithstanding
     * (pose_range.GUARD_SLACK_DEG). */
    const double inside = cos(half + 0.5e-5 / DEG_PER_RAD);
    int count = 0;
    for (int j = 0; j < POSE_LIMITS_JOINTS; ++j) {
        if (moved) moved[j] = 0;
        const pose_range_span *span = &pose_range_joints[j];
        const double n = sqrt(dot4(q[j], q[j]));
        if (span->count == 0 || !(n > 0.0) || !isfinite(n)) continue;
        double u[4], p[4];
        for (int i = 0; i < 4; ++i) u[i] = q[j][i] / n;
        const uint32_t last = s->last_nearest[j] < span->count ? s->last_nearest[j] : 0;
        range_point(span, last, p);
        if (fabs(dot4(u, p)) >= inside) continue;   /* near last frame's point: in range */
        s->last_nearest[j] = nearest_point(span, u, p);
        double d = dot4(u, p);
        if (fabs(d) >= inside) continue;
        if (d < 0.0) {
            d = -d;
            for (int i = 0; i < 4; ++i) p[i] = -p[i];
        }
        /* Along the great circle from p to u, stopping at the tolerance. */
        const double omega = acos(d), so = sin(omega);
        const double a = sin(omega - half) / so, b = sin(half) / so;
        double m = 0.0;
        for (int i = 0; i < 4; ++i) {
            u[i] = a * p[i] + b * u[i];
            m += u[i] * u[i];
        }
        m = 1.0 / sqrt(m);
        for (int i = 0; i < 4; ++i) q[j][i] = u[i] * m;
        if (moved) moved[j] = 1;
        ++count;
    }
    return count;
}
