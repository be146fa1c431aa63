/* The SMPL-24 skeleton table (smpl_skeleton.h). */
#include "smpl_skeleton.h"

#include <string.h>

typedef struct smpl_joint {
    const char *name;
    int parent;
    const char *humanoid_bone; /* Unity's HumanBodyBones name; NULL: drives no bone */
} smpl_joint;

/* A joint's rotation turns the bone that starts at it, which Unity names by the same place:
 * collar -> Shoulder, shoulder -> UpperArm, hip -> UpperLeg, foot -> Toes. */
static const smpl_joint JOINTS[MOCAP_JOINT_COUNT] = {
    {"pelvis", -1, "Hips"},
    {"left_hip", 0, "LeftUpperLeg"},
    {"right_hip", 0, "RightUpperLeg"},
    {"spine1", 0, "Spine"},
    {"left_knee", 1, "LeftLowerLeg"},
    {"right_knee", 2, "RightLowerLeg"},
    {"spine2", 3, "Chest"},
    {"left_ankle", 4, "LeftFoot"},
    {"right_ankle", 5, "RightFoot"},
    {"spine3", 6, "UpperChest"},
    {"left_foot", 7, "LeftToes"},
    {"right_foot", 8, "RightToes"},
    {"neck", 9, "Neck"},
    {"left_collar", 9, "LeftShoulder"},
    {"right_collar", 9, "RightShoulder"},
    {"head", 12, "Head"},
    {"left_shoulder", 13, "LeftUpperArm"},
    {"right_shoulder", 14, "RightUpperArm"},
    {"left_elbow", 16, "LeftLowerArm"},
    {"right_elbow", 17, "RightLowerArm"},
    {"left_wrist", 18, "LeftHand"},
    {"right_wrist", 19, "RightHand"},
    {"left_hand", 20, NULL},
    {"right_hand", 21, NULL},
};

static int in_range(int joint) { return joint >= 0 && joint < MOCAP_JOINT_COUNT; }

const char *smpl_joint_name(int joint) { return in_range(joint) ? JOINTS[joint].name : NULL; }

int smpl_joint_parent(int joint) { return in_range(joint) ? JOINTS[joint].parent : -2; }

const char *smpl_humanoid_bone(int joint) { return in_range(joint) ? JOINTS[joint].humanoid_bone : NULL; }

int smpl_joint_index(const char *name)
{
    if (!name) return -1;
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        if (strcmp(JOINTS[j].name, name) == 0) return j;
    return -1;
}

const char *mocap_humanoid_bone_name(int32_t joint) { return smpl_humanoid_bone((int)joint); }
