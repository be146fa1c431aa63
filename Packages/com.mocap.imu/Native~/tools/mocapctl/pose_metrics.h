/* Accuracy of solved poses against a pose truth, as `mocapctl replay --truth` prints it and
 * --metrics-json writes it: joint angle error (24 joints, the 15 DIP/TransPose joints, the 4 SIP
 * joints' global rotations), root-aligned joint position error, root drift over 2/5/10 s windows
 * (the pose root, and the integrated root_velocity), and jitter (third difference of joint
 * positions) beside the truth's own. Positions come from the engine's forward kinematics of the
 * model's skeleton. */
#ifndef MOCAPCTL_POSE_METRICS_H
#define MOCAPCTL_POSE_METRICS_H

#include <stddef.h>
#include <stdint.h>

#include "mocap_imu.h"
#include "pose_truth.h"
#include "skeleton_fk.h"

typedef struct pose_metrics {
    skeleton skeleton;
    double fps;
    uint64_t compared;
    double angle_all, angle_dip, sip, pos_cm;
    double jitter_sum, truth_jitter_sum;
    uint64_t jitter_n;
    double hist_p[3][MOCAP_JOINT_COUNT][3], hist_t[3][MOCAP_JOINT_COUNT][3];
    int hist_len;
    uint64_t last_frame_sequence;
    /* per compared pose, for the drift windows */
    double *pred_root, *vel_root, *true_root, *times;
    size_t cap;
} pose_metrics;

/* Empty metrics on the model's skeleton at its frame rate. 0, or 1 after printing why (a
 * skeleton the forward kinematics refuses); pose_metrics_free either way. */
int pose_metrics_init(pose_metrics *m, const mocap_model_info *info);
void pose_metrics_free(pose_metrics *m);

/* One solved pose against the truth at its time. */
void pose_metrics_add(pose_metrics *m, const mocap_pose *pose, const pose_truth_row *truth);

/* The figures on stdout. */
void pose_metrics_print(const pose_metrics *m, const char *truth_path);

/* The same figures as one JSON object in `path` (NaN, as with no pose, is null). 0 when
 * written, else 1 after saying why. */
int pose_metrics_write_json(const pose_metrics *m, const char *truth_path, const char *path);

#endif
