/* Poses as JSON lines and CSV (pose_files.h). */
#include "pose_files.h"

void pose_write_json_line(FILE *f, const mocap_pose *p)
{
    fprintf(f, "{\"sequence\":%llu,\"frame_sequence\":%llu,\"time_s\":%.6f,\"flags\":%u,"
               "\"root_position\":[%.6f,%.6f,%.6f],\"root_velocity\":[%.6f,%.6f,%.6f],"
               "\"foot_contact\":[%.4f,%.4f],\"joint_rotations\":[",
            (unsigned long long)p->sequence, (unsigned long long)p->frame_sequence, p->time_s,
            p->flags, p->root_position[0], p->root_position[1], p->root_position[2],
            p->root_velocity[0], p->root_velocity[1], p->root_velocity[2], p->foot_contact[0],
            p->foot_contact[1]);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        fprintf(f, "%s[%.6f,%.6f,%.6f,%.6f]", j ? "," : "", p->joint_rotations[j][0],
                p->joint_rotations[j][1], p->joint_rotations[j][2], p->joint_rotations[j][3]);
    fputs("],\"joint_positions\":[", f);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        fprintf(f, "%s[%.6f,%.6f,%.6f]", j ? "," : "", p->joint_positions[j][0],
                p->joint_positions[j][1], p->joint_positions[j][2]);
    fputs("]}\n", f);
}

void pose_write_csv_header(FILE *f, const mocap_model_info *info)
{
    fputs("sequence,frame_sequence,time_s,flags,root_x,root_y,root_z,vel_x,vel_y,vel_z,"
          "contact_left,contact_right", f);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        const char *n = info->joint_names[j];
        fprintf(f, ",%s_qw,%s_qx,%s_qy,%s_qz", n, n, n, n);
    }
    fputc('\n', f);
}

void pose_write_csv_line(FILE *f, const mocap_pose *p)
{
    fprintf(f, "%llu,%llu,%.6f,%u,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.4f,%.4f",
            (unsigned long long)p->sequence, (unsigned long long)p->frame_sequence, p->time_s,
            p->flags, p->root_position[0], p->root_position[1], p->root_position[2],
            p->root_velocity[0], p->root_velocity[1], p->root_velocity[2], p->foot_contact[0],
            p->foot_contact[1]);
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
        fprintf(f, ",%.6f,%.6f,%.6f,%.6f", p->joint_rotations[j][0], p->joint_rotations[j][1],
                p->joint_rotations[j][2], p->joint_rotations[j][3]);
    fputc('\n', f);
}
