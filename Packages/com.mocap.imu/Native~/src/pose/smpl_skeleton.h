/* The SMPL-24 skeleton of the pose-model contract: joint names, parents and the Unity humanoid
 * bone each joint drives. One table for the contract check, the VMC sender and (through
 * mocap_humanoid_bone_name) the C# bindings. */
#ifndef MOCAP_SMPL_SKELETON_H
#define MOCAP_SMPL_SKELETON_H

#include "mocap_imu.h"

/* The joint's contract name ("left_collar"); NULL outside 0..MOCAP_JOINT_COUNT-1. */
const char *smpl_joint_name(int joint);
/* The joint's parent (-1 for the pelvis); -2 outside 0..MOCAP_JOINT_COUNT-1. */
int smpl_joint_parent(int joint);
/* The Unity HumanBodyBones name of the bone the joint's rotation turns ("LeftShoulder"); NULL for
 * the two hand end points (left_hand, right_hand: the knuckles, no bone of their own) and outside
 * the joint range. */
const char *smpl_humanoid_bone(int joint);
/* The index of a contract joint name, or -1. */
int smpl_joint_index(const char *name);

#endif
