/* Streaming BVH writer for solved poses (SMPL-24 skeleton of the pose model).
 *
 * Shared by `mocapctl replay --out` and the editor export (issue 7).
 *
 * File layout
 *  - HIERARCHY: the joints depth-first from the root (the column order of MOTION), names and
 *    parents as the model's metadata gives them, OFFSETs = the model's rest offsets in METRES
 *    (model frame: right-handed, Y up, the character faces +Z, X is its left). The root's OFFSET
 *    is (0, pelvis height, 0) as in the metadata. Blender imports BVH at 1 unit = 1 scene unit,
 *    so with the default scale 1.0 the character is 1:1 in metres; its default axis conversion
 *    (forward -Z, up Y) stands the character up facing Blender's -Y (towards the front view).
 *    Leaf joints get an End Site half as long as their own bone (minimum 5 cm), continuing it.
 *  - Channels: the root has Xposition Yposition Zposition then three rotations; every other joint
 *    three rotations. Rotation channels are intrinsic Euler angles in degrees in the listed
 *    order (ZXY: R = Rz * Rx * Ry, the usual mocap order; or XYZ: R = Rx * Ry * Rz), each
 *    rotation mapping the joint frame into its parent frame; the rest pose (all zeros) is the
 *    model's T-pose. Angles are kept continuous from frame to frame (of the two Euler solutions
 *    and their 360-degree shifts, the one nearest the previous frame), so interpolation in an
 *    animation tool does not spin.
 *  - Root position channels: the root (pelvis) position in the model frame, metres (absolute:
 *    they replace the root OFFSET, as Blender and training/bvh.py read them).
 *  - Frame Time: 1 / the model's frame rate.
 *
 * Crash safety: the header is written at open with a fixed-width frame count; frames are appended
 * one text line each, and every `flush_every` frames (default 1: every frame) the stream is
 * flushed and the frame count in the header is rewritten to the number of complete lines. After a
 * crash the file is a valid BVH of every frame up to the last flush.
 *
 * Threads: one writer is used by one thread at a time. Errors: status + mocap_last_error(). */
#ifndef MOCAP_BVH_WRITER_H
#define MOCAP_BVH_WRITER_H

#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BVH_MAX_JOINTS 64
#define BVH_NAME_CAP 32

typedef enum bvh_rotation_order {
    BVH_ORDER_ZXY = 0, /* "Zrotation Xrotation Yrotation": R = Rz Rx Ry (default) */
    BVH_ORDER_XYZ = 1  /* "Xrotation Yrotation Zrotation": R = Rx Ry Rz */
} bvh_rotation_order;

/* A skeleton in the pose model's joint order: parents[j] < j for j > 0, parents[0] = -1. */
typedef struct bvh_skeleton {
    int32_t joint_count;                 /* 1..BVH_MAX_JOINTS */
    char names[BVH_MAX_JOINTS][BVH_NAME_CAP];
    int32_t parents[BVH_MAX_JOINTS];
    float offsets[BVH_MAX_JOINTS][3];    /* metres, parent frame at rest; [0]: root rest position */
} bvh_skeleton;

/* The model's SMPL-24 skeleton (names, parents, rest offsets) from its metadata. */
mocap_status bvh_skeleton_from_model_info(const mocap_model_info *info, bvh_skeleton *out);

typedef struct bvh_writer bvh_writer;

/* Creates (truncates) path and writes the header. frame_time_s > 0 (1 / the model's frame
 * rate). MOCAP_ERR_INVALID_ARGUMENT for a bad skeleton (names, parents), MOCAP_ERR_IO when the
 * file cannot be written (the message names it). */
mocap_status bvh_writer_open(const char *path, const bvh_skeleton *skeleton, double frame_time_s,
                             bvh_rotation_order order, bvh_writer **out);
/* Frames between flushes (and header count updates); 1 by default; 0 is taken as 1. */
void bvh_writer_set_flush_every(bvh_writer *w, uint32_t frames);

/* Appends one frame: root_position (metres, model frame) and one unit quaternion (w,x,y,z) per
 * joint in the skeleton's joint order: joint 0 global, the others local to their parent.
 * Quaternions need not be normalised (they are); a zero or non-finite one is written as
 * identity. */
mocap_status bvh_writer_append(bvh_writer *w, const float root_position[3],
                               const float (*rotations)[4]);
/* Appends a solved pose (skeleton of MOCAP_JOINT_COUNT joints): root_position and
 * joint_rotations. */
mocap_status bvh_writer_append_pose(bvh_writer *w, const mocap_pose *pose);

/* Flushes and updates the frame count in the header now. */
mocap_status bvh_writer_flush(bvh_writer *w);
uint64_t bvh_writer_frames(const bvh_writer *w);

/* Flushes, writes the final frame count, closes the file and frees the writer (NULL accepted).
 * Returns the first error met while writing, if any. */
mocap_status bvh_writer_close(bvh_writer *w);

/* Intrinsic Euler angles (radians) of the row-major rotation matrix m in `order`
 * (R = R_a(angles[0]) R_b(angles[1]) R_c(angles[2]) for order "abc"). With `previous` non-NULL
 * the solution (of the two, with 2*pi shifts) nearest to it is returned. Exposed for tests. */
void bvh_euler_from_matrix(const double m[9], bvh_rotation_order order, const double *previous,
                           double angles[3]);

#ifdef __cplusplus
}
#endif
#endif
