/* The pose guard: a joint the model bends where no person's joint goes is turned back to the
 * edge of what people do. Each joint's local rotation is compared with the rotations of its
 * range (pose_range_table.h); one further than the tolerance from all of them is rotated along
 * the shortest way towards the nearest until it is the tolerance away. A pose inside the range
 * passes bit for bit unchanged. No allocation; the state only remembers, per joint, which point
 * was nearest last time, so a joint that stays near it costs one dot product.
 * Unit-tested in tests/test_pose_limits.cpp; the same rule in numpy is training's
 * pose_range.guard_quats. */
#ifndef MOCAP_POSE_LIMITS_H
#define MOCAP_POSE_LIMITS_H

#include <stdint.h>

#include "pose_range_table.h"

#ifdef __cplusplus
extern "C" {
#endif

#define POSE_LIMITS_JOINTS POSE_RANGE_JOINTS

typedef struct pose_limits_state {
    uint32_t last_nearest[POSE_LIMITS_JOINTS];   /* offset in the joint's span */
} pose_limits_state;

void pose_limits_reset(pose_limits_state *s);

/* Guards the local rotations q (w, x, y, z; joint 0 is the root's global orientation and is left
 * alone) in place; tolerance_deg > 0. Returns how many joints it turned; moved[j] (may be NULL)
 * says which. Non-finite rotations are left for the caller's checks. */
int pose_limits_apply(pose_limits_state *s, double tolerance_deg, double (*q)[4], uint8_t *moved);

/* The angle (deg) from rotation q of joint j to the nearest rotation of its range; -1 for a joint
 * without one. */
double pose_limits_distance_deg(int joint, const double q[4]);

#ifdef __cplusplus
}
#endif
#endif
