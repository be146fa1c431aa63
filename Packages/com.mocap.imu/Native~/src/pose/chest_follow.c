#include "chest_follow.h"

#include <math.h>

#include "mocap_math.h"

#define NECK 12
#define LEFT_COLLAR 13
#define RIGHT_COLLAR 14
#define HEAD 15
#define LEFT_SHOULDER 16
#define RIGHT_SHOULDER 17

/* out = q^t, the rotation t of the way along q's shortest turn (exact at small angles, where a
 * slerp falls back to a linear blend). */
static void turn_power(double out[4], const double q[4], double t)
{
    const double sign = q[0] < 0.0 ? -1.0 : 1.0;
    const double w = sign * q[0], x = sign * q[1], y = sign * q[2], z = sign * q[3];
    const double v = sqrt(x * x + y * y + z * z);
    if (v < 1e-15) {
        quat_identity(out);
        return;
    }
    const double half = t * atan2(v, w), k = sin(half) / v;
    out[0] = cos(half);
    out[1] = x * k;
    out[2] = y * k;
    out[3] = z * k;
}

/* out = conj(parent) * child_global: a child's local rotation under a parent's global one. */
static void local_under(double out[4], const double parent[4], const double child_global[4])
{
    double inv[4];
    quat_conjugate(inv, parent);
    quat_multiply(out, inv, child_global);
}

int chest_follow_apply(double (*q)[4], const double chest[4], double share)
{
    if (!(share >= 0.0 && share <= 1.0)) return -1;
    double sensed[4] = {chest[0], chest[1], chest[2], chest[3]};
    if (quat_normalize(sensed) != 0) return -1;
    if (share == 0.0) return 0;

    /* The globals the rule reads, before it turns anything. */
    double g3[4], g6[4], g9[4], g12[4], g13[4], g14[4], head[4], left_arm[4], right_arm[4];
    quat_multiply(g3, q[CHEST_FOLLOW_PELVIS], q[CHEST_FOLLOW_SPINE1]);
    quat_multiply(g6, g3, q[CHEST_FOLLOW_SPINE2]);
    quat_multiply(g9, g6, q[CHEST_FOLLOW_SPINE3]);
    quat_multiply(g12, g9, q[NECK]);
    quat_multiply(g13, g9, q[LEFT_COLLAR]);
    quat_multiply(g14, g9, q[RIGHT_COLLAR]);
    quat_multiply(head, g12, q[HEAD]);
    quat_multiply(left_arm, g13, q[LEFT_SHOULDER]);
    quat_multiply(right_arm, g14, q[RIGHT_SHOULDER]);

    /* The turn in the world frame that takes the chest bone onto the sensor, and its share. */
    double inv9[4], turn[4], part[3][4];
    quat_conjugate(inv9, g9);
    quat_multiply(turn, sensed, inv9);
    turn_power(part[0], turn, share * CHEST_FOLLOW_SPINE1_PART);
    turn_power(part[1], turn, share * CHEST_FOLLOW_SPINE2_PART);
    turn_power(part[2], turn, share);

    double n3[4], n6[4], n9[4];
    quat_multiply(n3, part[0], g3);
    quat_multiply(n6, part[1], g6);
    quat_multiply(n9, part[2], g9);
    local_under(q[CHEST_FOLLOW_SPINE1], q[CHEST_FOLLOW_PELVIS], n3);
    local_under(q[CHEST_FOLLOW_SPINE2], n3, n6);
    local_under(q[CHEST_FOLLOW_SPINE3], n6, n9);
    for (int j = CHEST_FOLLOW_SPINE1; j <= CHEST_FOLLOW_SPINE3; j += 3) quat_normalize(q[j]);

    /* Neck and collars keep their local rotations; head and upper arms their global ones. */
    double m12[4], m13[4], m14[4];
    quat_multiply(m12, n9, q[NECK]);
    quat_multiply(m13, n9, q[LEFT_COLLAR]);
    quat_multiply(m14, n9, q[RIGHT_COLLAR]);
    local_under(q[HEAD], m12, head);
    local_under(q[LEFT_SHOULDER], m13, left_arm);
    local_under(q[RIGHT_SHOULDER], m14, right_arm);
    quat_normalize(q[HEAD]);
    quat_normalize(q[LEFT_SHOULDER]);
    quat_normalize(q[RIGHT_SHOULDER]);
    return 0;
}
