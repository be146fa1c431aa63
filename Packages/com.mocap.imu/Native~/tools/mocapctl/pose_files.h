/* Solved poses as text for scripts: one JSON object per line (replay --json) or one CSV line
 * (replay --pose-csv). */
#ifndef MOCAPCTL_POSE_FILES_H
#define MOCAPCTL_POSE_FILES_H

#include <stdio.h>

#include "mocap_imu.h"

/* sequence, frame_sequence, time_s, flags, root_position, root_velocity, foot_contact,
 * joint_rotations (24 x w x y z), joint_positions (24 x x y z). */
void pose_write_json_line(FILE *f, const mocap_pose *pose);

/* The header names the joints as the model does. Columns: sequence .. contact_right, then
 * NAME_qw NAME_qx NAME_qy NAME_qz per joint. */
void pose_write_csv_header(FILE *f, const mocap_model_info *info);
void pose_write_csv_line(FILE *f, const mocap_pose *pose);

#endif
