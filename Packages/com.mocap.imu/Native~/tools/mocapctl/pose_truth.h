/* The pose truth CSV `python3 -m training synth-capture` writes beside a capture
 * (CAPTURE.truth.csv): per row the session time, the motion, the root position (x y z) and the
 * 24 joints' rotations (qw qx qy qz; joint 0 global, the others local). */
#ifndef MOCAPCTL_POSE_TRUTH_H
#define MOCAPCTL_POSE_TRUTH_H

#include <stddef.h>

#include "mocap_imu.h"

#define POSE_TRUTH_COLUMNS (5 + MOCAP_JOINT_COUNT * 4)

typedef struct pose_truth_row {
    double t;
    int motion; /* 0: standing still (the prelude) */
    double root[3];
    double q[MOCAP_JOINT_COUNT][4];
} pose_truth_row;

typedef struct pose_truth {
    pose_truth_row *rows;
    size_t count, cursor;
} pose_truth;

/* Numbers on the first data line of a CSV: 0 when none, -1 when it does not open. Tells a pose
 * truth (POSE_TRUTH_COLUMNS) from synth's sensor truth. */
int csv_first_row_columns(const char *path);

/* Reads `path` (rows with another column count skipped, quaternions normalised). 0, or -1 after
 * printing why (nothing to free then); pose_truth_free releases a loaded table. */
int pose_truth_load(const char *path, pose_truth *truth);
void pose_truth_free(pose_truth *truth);

/* The truth at time t (slerp between rows): 0, or -1 outside the table's time range. Queries
 * must come in time order. */
int pose_truth_at(pose_truth *truth, double t, pose_truth_row *out);

#endif
