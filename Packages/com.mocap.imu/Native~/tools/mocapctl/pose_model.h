/* The pose model of mocapctl's pose commands: the shipped one unless --model names another. */
#ifndef MOCAPCTL_POSE_MODEL_H
#define MOCAPCTL_POSE_MODEL_H

#include <stddef.h>

#include "mocap_imu.h"

/* The shipped default model (int8 weights), relative to the repository root. */
#define MOCAPCTL_SHIPPED_MODEL "Packages/com.mocap.imu/Runtime/Models/mocap_pose_int8.onnx"

/* The shipped model: $MOCAP_MODEL, else found above the executable, else above the current
 * directory, else where the build was configured from (MOCAP_SHIPPED_MODEL). 0 with its path in
 * `out`, or -1 with the places it looked in `out`. */
int pose_model_default_path(char *out, size_t cap);

/* Opens `model_arg` (NULL: the shipped model) and prints what it is on stdout. 0, or 1 after
 * printing why not. */
int pose_model_open(const char *model_arg, mocap_model **model, mocap_model_info *info);

#endif
