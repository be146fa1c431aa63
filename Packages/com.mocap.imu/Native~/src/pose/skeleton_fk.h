/* Forward kinematics of the pose model's skeleton (the parents and rest offsets in the model's
 * metadata, docs/model-contract.md), with quaternions (w, x, y, z) in double precision.
 *
 * Joint 0's rotation is global (model frame); every other joint's rotation is local, relative to
 * its parent, identity = rest pose. Joint j sits at its parent's position plus the parent's
 * global rotation applied to rest offset j (the same rule as training/model.py's
 * forward_kinematics_torch). Pure functions, no allocation. */
#ifndef MOCAP_SKELETON_FK_H
#define MOCAP_SKELETON_FK_H

#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SKELETON_MAX_JOINTS MOCAP_JOINT_COUNT
/* Contract joints whose contact the model predicts (left_foot, right_foot). */
#define SKELETON_LEFT_FOOT 10
#define SKELETON_RIGHT_FOOT 11

typedef struct skeleton {
    int count;
    int parents[SKELETON_MAX_JOINTS];
    double offsets[SKELETON_MAX_JOINTS][3];
    /* Rest pose with joint 0 at offsets[0] (the pelvis height above a floor at y = 0). */
    double rest_positions[SKELETON_MAX_JOINTS][3];
    /* Height of each foot joint above the sole in the rest pose (rest y, at least 0). */
    double foot_height[2];
} skeleton;

/* Validates the topology (parents[0] == -1, 0 <= parents[j] < j) and finite offsets.
 * Returns MOCAP_OK or MOCAP_ERR_FORMAT with a message naming the joint. */
mocap_status skeleton_init(skeleton *sk, const int32_t *parents, const float (*offsets)[3],
                           int count);

/* local[j]: joint rotations (joint 0 global). root: position of joint 0. Outputs may be NULL. */
void skeleton_fk(const skeleton *sk, const double (*local)[4], const double root[3],
                 double (*global_out)[4], double (*positions_out)[3]);

/* Row-major 3x3 float matrix -> nearest unit quaternion with w >= 0 (orthonormalised by the
 * quaternion round trip). Returns 0, or -1 for a non-finite or degenerate matrix (identity then). */
int skeleton_matrix_to_quat(const float m[9], double q[4]);

#ifdef __cplusplus
}
#endif
#endif
