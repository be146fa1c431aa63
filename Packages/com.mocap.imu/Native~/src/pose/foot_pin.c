/* Foot pinning by two-bone inverse kinematics. The rule is stated in foot_pin.h. */
#include "foot_pin.h"

#include <math.h>
#include <string.h>

#include "mocap_math.h"

static const int k_chain[2][4] = {
    {FOOT_PIN_LEFT_HIP, FOOT_PIN_LEFT_KNEE, FOOT_PIN_LEFT_ANKLE, SKELETON_LEFT_FOOT},
    {FOOT_PIN_RIGHT_HIP, FOOT_PIN_RIGHT_KNEE, FOOT_PIN_RIGHT_ANKLE, SKELETON_RIGHT_FOOT},
};

void foot_pin_reset(foot_pin_state *s) { memset(s, 0, sizeof *s); }

static void sub3(double out[3], const double a[3], const double b[3])
{
    for (int k = 0; k < 3; ++k) out[k] = a[k] - b[k];
}

/* The shortest rotation taking direction u onto direction v (neither need be unit). */
static void quat_between(double out[4], const double u[3], const double v[3])
{
    double nu = vec3_norm(u), nv = vec3_norm(v);
    if (nu < 1e-12 || nv < 1e-12) {
        quat_identity(out);
        return;
    }
    double c[3];
    vec3_cross(c, u, v);
    double w = nu * nv + vec3_dot(u, v);
    if (w < 1e-9 * nu * nv) {   /* opposite: half a turn about any axis normal to u */
        double axis[3] = {0.0, -u[2], u[1]};
        if (vec3_norm(axis) < 1e-9 * nu) axis[0] = -u[1], axis[1] = u[0], axis[2] = 0.0;
        quat_from_axis_angle(out, axis, 3.14159265358979323846);
        return;
    }
    double q[4] = {w, c[0], c[1], c[2]};
    double n = quat_norm(q);
    for (int k = 0; k < 4; ++k) out[k] = q[k] / n;
}

static double clampd(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

/* foot_pin_reach on the pose's global rotations g and positions p (its forward kinematics).
 * Only the leg's own entries of g and p are read and only its hip, knee and ankle in q are
 * written, so g and p stay valid for the other leg. */
static double reach_leg(const skeleton *sk, int hip, int knee, int ankle, int foot,
                        const double (*g)[4], const double (*p)[3], const double goal[3],
                        double (*q)[4])
{
    /* The ankle goal that puts the foot on its goal with the foot's bone as it is. */
    double foot_bone[3], ankle_goal[3];
    sub3(foot_bone, p[foot], p[ankle]);
    sub3(ankle_goal, goal, foot_bone);

    double thigh[3], shin[3], hip_to_ankle[3], hip_to_goal[3];
    sub3(thigh, p[knee], p[hip]);
    sub3(shin, p[ankle], p[knee]);
    sub3(hip_to_ankle, p[ankle], p[hip]);
    sub3(hip_to_goal, ankle_goal, p[hip]);
    const double a = vec3_norm(thigh), b = vec3_norm(shin);
    double knee_turn[4];
    quat_identity(knee_turn);
    if (a > 1e-9 && b > 1e-9) {
        /* Open or close the knee until hip-to-ankle has the goal's length. The knee bends
         * forward about its own x axis (SMPL: flexion turns the shin backwards, about +x). A knee
         * bent forward turns in the plane of thigh and shin, exactly; a straight or
         * hyperextended one turns about that axis, so that shortening the leg never bends it
         * further backwards. */
        const double reach_max = a + b - 1e-6, reach_min = fabs(a - b) + 1e-6;
        const double d = clampd(vec3_norm(hip_to_goal), reach_min, reach_max);
        const double c0 = vec3_norm(hip_to_ankle);
        const double now = acos(clampd((a * a + b * b - c0 * c0) / (2 * a * b), -1.0, 1.0));
        const double want = acos(clampd((a * a + b * b - d * d) / (2 * a * b), -1.0, 1.0));
        const double x_axis[3] = {1.0, 0.0, 0.0};
        double flexion_axis[3], plane_axis[3], minus_thigh[3] = {-thigh[0], -thigh[1], -thigh[2]};
        quat_rotate(flexion_axis, g[knee], x_axis);
        vec3_cross(plane_axis, minus_thigh, shin);   /* turning about it opens the knee */
        if (vec3_dot(plane_axis, flexion_axis) < -1e-3 * a * b) {
            quat_from_axis_angle(knee_turn, plane_axis, want - now);
        } else {
            /* Signed flexion: 0 straight, negative hyperextended. */
            const double flexion_now = -(3.14159265358979323846 - now);
            const double flexion_want = 3.14159265358979323846 - want;
            quat_from_axis_angle(knee_turn, flexion_axis, flexion_want - flexion_now);
        }
    }
    double new_shin[3], new_ankle[3];
    quat_rotate(new_shin, knee_turn, shin);
    for (int k = 0; k < 3; ++k) new_ankle[k] = thigh[k] + new_shin[k];   /* from the hip */
    double hip_turn[4];
    quat_between(hip_turn, new_ankle, hip_to_goal);

    double g_hip[4], g_knee[4], tmp[4], inv[4];
    quat_multiply(g_hip, hip_turn, g[hip]);
    quat_multiply(tmp, knee_turn, g[knee]);
    quat_multiply(g_knee, hip_turn, tmp);
    quat_conjugate(inv, g[sk->parents[hip]]);
    quat_multiply(q[hip], inv, g_hip);
    quat_conjugate(inv, g_hip);
    quat_multiply(q[knee], inv, g_knee);
    quat_conjugate(inv, g_knee);
    quat_multiply(q[ankle], inv, g[ankle]);   /* the ankle keeps its global rotation */

    /* Where the foot is now: the hip plus the turned hip-to-ankle, plus the unchanged foot bone. */
    double turned[3], left[3];
    quat_rotate(turned, hip_turn, new_ankle);
    for (int k = 0; k < 3; ++k) left[k] = goal[k] - (p[hip][k] + turned[k] + foot_bone[k]);
    return vec3_norm(left);
}

double foot_pin_reach(const skeleton *sk, int hip, int knee, int ankle, int foot,
                      const double root[3], const double goal[3], double (*q)[4])
{
    double g[SKELETON_MAX_JOINTS][4], p[SKELETON_MAX_JOINTS][3];
    skeleton_fk(sk, (const double (*)[4])q, root, g, p);
    return reach_leg(sk, hip, knee, ankle, foot, (const double (*)[4])g, (const double (*)[3])p, goal, q);
}

static int has_legs(const skeleton *sk)
{
    for (int f = 0; f < 2; ++f) {
        const int *c = k_chain[f];
        if (c[3] >= sk->count || sk->parents[c[3]] != c[2] || sk->parents[c[2]] != c[1] ||
            sk->parents[c[1]] != c[0])
            return 0;
    }
    return 1;
}

int foot_pin_apply(foot_pin_state *s, const foot_pin_params *p, const skeleton *sk,
                   const double root[3], const int planted[2], double (*q)[4])
{
    if (!(p->max_offset > 0.0) || !has_legs(sk)) return 0;
    double g[SKELETON_MAX_JOINTS][4], pos[SKELETON_MAX_JOINTS][3];
    skeleton_fk(sk, (const double (*)[4])q, root, g, pos);
    const double fade = p->release_s > 0.0 ? exp(-p->dt / p->release_s) : 0.0;
    int moved = 0;
    for (int f = 0; f < 2; ++f) {
        const double *predicted = pos[k_chain[f][3]];
        if (planted[f]) {
            /* Touchdown: held where it is shown now, so the pin starts without a jump. */
            if (!s->planted[f])
                for (int k = 0; k < 3; ++k) s->target[f][k] = predicted[k] + s->offset[f][k];
            sub3(s->offset[f], s->target[f], predicted);
            /* The held point creeps after the pose at up to creep_speed, and gives way to stay
             * within max_offset of it. */
            const double creep = p->creep_speed * p->dt, o = vec3_norm(s->offset[f]);
            double keep = o > creep ? 1.0 - creep / o : 0.0;
            if (keep * o > p->max_offset) keep = p->max_offset / o;
            for (int k = 0; k < 3; ++k) {
                s->offset[f][k] *= keep;
                s->target[f][k] = predicted[k] + s->offset[f][k];
            }
        } else {
            for (int k = 0; k < 3; ++k) s->offset[f][k] *= fade;
        }
        s->planted[f] = planted[f] != 0;
        const double held = vec3_norm(s->offset[f]);
        if (!isfinite(held)) {   /* a non-finite pose or root: start afresh from the next one */
            memset(s->offset[f], 0, sizeof s->offset[f]);
            s->planted[f] = 0;
            continue;
        }
        if (held < 1e-5) continue;
        double goal[3];
        for (int k = 0; k < 3; ++k) goal[k] = predicted[k] + s->offset[f][k];
        reach_leg(sk, k_chain[f][0], k_chain[f][1], k_chain[f][2], k_chain[f][3],
                  (const double (*)[4])g, (const double (*)[3])pos, goal, q);
        ++moved;
    }
    return moved;
}
