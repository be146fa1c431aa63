/* VMC protocol sender (public API in mocap_imu.h, "Streaming and export"): a solved SMPL-24 pose
 * as one OSC bundle of /VMC/Ext/OK, /VMC/Ext/T, /VMC/Ext/Root/Pos and one /VMC/Ext/Bone/Pos per
 * mapped HumanBodyBones bone, in Unity's coordinates, sent over UDP. Internal pieces for tests. */
#ifndef MOCAP_VMC_SENDER_H
#define MOCAP_VMC_SENDER_H

#include <stddef.h>
#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define VMC_BONE_COUNT 22      /* SMPL-24 minus left_hand / right_hand */
#define VMC_BUNDLE_CAPACITY 4096

/* HumanBodyBones name of an SMPL joint name ("pelvis" -> "Hips"), NULL when it has none. */
const char *vmc_bone_name(const char *smpl_joint);
/* The i-th pair of the mapping (0 <= i < VMC_BONE_COUNT), in SMPL joint order. */
void vmc_bone_pair(int i, const char **smpl_joint, const char **bone);

/* Model frame (right-handed, Y up, +Z forward) -> Unity (left-handed, Y up, +Z forward): mirror X. */
void vmc_position_to_unity(const float model[3], float unity[3]);
/* (w,x,y,z) in the model frame -> Unity quaternion in VMC order (x,y,z,w) = (x,-y,-z,w).
 * A zero or non-finite quaternion becomes identity. */
void vmc_rotation_to_unity(const float model_wxyz[4], float unity_xyzw[4]);

/* The bundle of one pose into buf (no allocation); returns its size, 0 when it does not fit or
 * info has none of the SMPL joint names. *bones receives the Bone/Pos message count. */
size_t vmc_encode_pose(uint8_t *buf, size_t cap, const mocap_model_info *info,
                       const mocap_pose *pose, int32_t calibration_state, uint32_t *bones);

#ifdef __cplusplus
}
#endif
#endif
