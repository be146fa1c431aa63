/* Version information and the layout table bindings use to check their struct mirrors. */
#include <stddef.h>

#include "mocap_imu.h"

#ifndef MOCAP_VERSION_STRING
#define MOCAP_VERSION_STRING "0.0.0"
#endif

int32_t mocap_api_version(void) { return MOCAP_API_VERSION; }
int32_t mocap_api_version_minor(void) { return MOCAP_API_VERSION_MINOR; }
const char *mocap_version_string(void) { return MOCAP_VERSION_STRING; }

#define STRUCT_ROW(type) {#type, "", 0, (uint32_t)sizeof(type)}
#define FIELD_ROW(type, field) \
    {#type, #field, (uint32_t)offsetof(type, field), (uint32_t)sizeof(((type *)0)->field)}

static const mocap_field_layout layout_table[] = {
    STRUCT_ROW(mocap_sensor_frame),
    FIELD_ROW(mocap_sensor_frame, bone_orientation),
    FIELD_ROW(mocap_sensor_frame, bone_acceleration),
    FIELD_ROW(mocap_sensor_frame, sensor_orientation),
    FIELD_ROW(mocap_sensor_frame, world_specific_force),
    FIELD_ROW(mocap_sensor_frame, angular_rate),
    FIELD_ROW(mocap_sensor_frame, age_s),
    FIELD_ROW(mocap_sensor_frame, flags),
    FIELD_ROW(mocap_sensor_frame, node_id),

    STRUCT_ROW(mocap_frame),
    FIELD_ROW(mocap_frame, sequence),
    FIELD_ROW(mocap_frame, time_s),
    FIELD_ROW(mocap_frame, newest_receive_ns),
    FIELD_ROW(mocap_frame, emitted_ns),
    FIELD_ROW(mocap_frame, flags),
    FIELD_ROW(mocap_frame, fresh_mask),
    FIELD_ROW(mocap_frame, sensors),

    STRUCT_ROW(mocap_session_config),
    FIELD_ROW(mocap_session_config, struct_size),
    FIELD_ROW(mocap_session_config, source_kind),
    FIELD_ROW(mocap_session_config, path),
    FIELD_ROW(mocap_session_config, baud),
    FIELD_ROW(mocap_session_config, hid_vendor_id),
    FIELD_ROW(mocap_session_config, hid_product_id),
    FIELD_ROW(mocap_session_config, node_ids),
    FIELD_ROW(mocap_session_config, imusol_layout),
    FIELD_ROW(mocap_session_config, world_frame),
    FIELD_ROW(mocap_session_config, output_rate_hz),
    FIELD_ROW(mocap_session_config, hold_latency_s),
    FIELD_ROW(mocap_session_config, stale_after_s),
    FIELD_ROW(mocap_session_config, kalman_process_noise),
    FIELD_ROW(mocap_session_config, kalman_measurement_noise),
    FIELD_ROW(mocap_session_config, replay_realtime),
    FIELD_ROW(mocap_session_config, replay_speed),
    FIELD_ROW(mocap_session_config, auto_reconnect),
    FIELD_ROW(mocap_session_config, capture_path),

    STRUCT_ROW(mocap_session_stats),
    FIELD_ROW(mocap_session_stats, bytes_received),
    FIELD_ROW(mocap_session_stats, frames_decoded),
    FIELD_ROW(mocap_session_stats, crc_failures),
    FIELD_ROW(mocap_session_stats, bytes_skipped),
    FIELD_ROW(mocap_session_stats, unknown_packets),
    FIELD_ROW(mocap_session_stats, samples_decoded),
    FIELD_ROW(mocap_session_stats, samples_rejected),
    FIELD_ROW(mocap_session_stats, frames_emitted),
    FIELD_ROW(mocap_session_stats, frames_dropped),
    FIELD_ROW(mocap_session_stats, bytes_dropped),
    FIELD_ROW(mocap_session_stats, reconnects),
    FIELD_ROW(mocap_session_stats, capture_bytes_written),
    FIELD_ROW(mocap_session_stats, replay_chunks_skipped),
    FIELD_ROW(mocap_session_stats, connection_state),
    FIELD_ROW(mocap_session_stats, capture_error),
    FIELD_ROW(mocap_session_stats, sensors_seen_mask),
    FIELD_ROW(mocap_session_stats, replay_tail_damaged),
    FIELD_ROW(mocap_session_stats, last_error),

    STRUCT_ROW(mocap_sensor_quality),
    FIELD_ROW(mocap_sensor_quality, gyro_rms_dps),
    FIELD_ROW(mocap_sensor_quality, orientation_spread_deg),
    FIELD_ROW(mocap_sensor_quality, accel_norm_error),
    FIELD_ROW(mocap_sensor_quality, tilt_deg),
    FIELD_ROW(mocap_sensor_quality, samples),
    FIELD_ROW(mocap_sensor_quality, ok),

    STRUCT_ROW(mocap_calibration_report),
    FIELD_ROW(mocap_calibration_report, step),
    FIELD_ROW(mocap_calibration_report, state),
    FIELD_ROW(mocap_calibration_report, progress),
    FIELD_ROW(mocap_calibration_report, seconds_remaining),
    FIELD_ROW(mocap_calibration_report, sensors),
    FIELD_ROW(mocap_calibration_report, reason),

    STRUCT_ROW(mocap_calibration),
    FIELD_ROW(mocap_calibration, struct_size),
    FIELD_ROW(mocap_calibration, valid_mask),
    FIELD_ROW(mocap_calibration, heading_mask),
    FIELD_ROW(mocap_calibration, reserved),
    FIELD_ROW(mocap_calibration, world_to_model),
    FIELD_ROW(mocap_calibration, sensor_to_bone),
    FIELD_ROW(mocap_calibration, acceleration_offset),

    STRUCT_ROW(mocap_model_options),
    FIELD_ROW(mocap_model_options, struct_size),
    FIELD_ROW(mocap_model_options, execution_provider),
    FIELD_ROW(mocap_model_options, intra_op_threads),
    FIELD_ROW(mocap_model_options, optimization_level),
    FIELD_ROW(mocap_model_options, cuda_device),
    FIELD_ROW(mocap_model_options, onnxruntime_path),

    STRUCT_ROW(mocap_model_info),
    FIELD_ROW(mocap_model_info, contract_version),
    FIELD_ROW(mocap_model_info, frame_rate),
    FIELD_ROW(mocap_model_info, state_layers),
    FIELD_ROW(mocap_model_info, state_size),
    FIELD_ROW(mocap_model_info, joint_parents),
    FIELD_ROW(mocap_model_info, rest_offsets),
    FIELD_ROW(mocap_model_info, joint_names),
    FIELD_ROW(mocap_model_info, precision),
    FIELD_ROW(mocap_model_info, model_name),

    STRUCT_ROW(mocap_solver_config),
    FIELD_ROW(mocap_solver_config, struct_size),
    FIELD_ROW(mocap_solver_config, contact_threshold),
    FIELD_ROW(mocap_solver_config, floor_height),
    FIELD_ROW(mocap_solver_config, drift_correction),
    FIELD_ROW(mocap_solver_config, require_calibration),
    FIELD_ROW(mocap_solver_config, smoothing_min_cutoff_hz),
    FIELD_ROW(mocap_solver_config, smoothing_beta),

    STRUCT_ROW(mocap_solver_stats),
    FIELD_ROW(mocap_solver_stats, ticks),
    FIELD_ROW(mocap_solver_stats, batched_calls),
    FIELD_ROW(mocap_solver_stats, max_batch),
    FIELD_ROW(mocap_solver_stats, frames_solved),
    FIELD_ROW(mocap_solver_stats, frames_uncalibrated),
    FIELD_ROW(mocap_solver_stats, frames_nonfinite),
    FIELD_ROW(mocap_solver_stats, outputs_nonfinite),
    FIELD_ROW(mocap_solver_stats, poses_dropped),
    FIELD_ROW(mocap_solver_stats, run_failures),
    FIELD_ROW(mocap_solver_stats, solve_ns_total),
    FIELD_ROW(mocap_solver_stats, solve_ns_max),
    FIELD_ROW(mocap_solver_stats, run_ns_total),
    FIELD_ROW(mocap_solver_stats, last_run_status),
    FIELD_ROW(mocap_solver_stats, reserved),
    FIELD_ROW(mocap_solver_stats, first_run_error),
    FIELD_ROW(mocap_solver_stats, last_run_error),

    STRUCT_ROW(mocap_pose),
    FIELD_ROW(mocap_pose, sequence),
    FIELD_ROW(mocap_pose, frame_sequence),
    FIELD_ROW(mocap_pose, time_s),
    FIELD_ROW(mocap_pose, character),
    FIELD_ROW(mocap_pose, flags),
    FIELD_ROW(mocap_pose, joint_rotations),
    FIELD_ROW(mocap_pose, joint_positions),
    FIELD_ROW(mocap_pose, root_position),
    FIELD_ROW(mocap_pose, root_velocity),
    FIELD_ROW(mocap_pose, foot_contact),
    FIELD_ROW(mocap_pose, newest_receive_ns),
    FIELD_ROW(mocap_pose, frame_emitted_ns),
    FIELD_ROW(mocap_pose, pose_emitted_ns),

    STRUCT_ROW(mocap_vmc_options),
    FIELD_ROW(mocap_vmc_options, struct_size),
    FIELD_ROW(mocap_vmc_options, max_rate_hz),
    FIELD_ROW(mocap_vmc_options, allow_remote),
    FIELD_ROW(mocap_vmc_options, calibration_state),

    STRUCT_ROW(mocap_vmc_stats),
    FIELD_ROW(mocap_vmc_stats, poses),
    FIELD_ROW(mocap_vmc_stats, bundles_sent),
    FIELD_ROW(mocap_vmc_stats, skipped_rate),
    FIELD_ROW(mocap_vmc_stats, send_failures),
    FIELD_ROW(mocap_vmc_stats, bytes_sent),
    FIELD_ROW(mocap_vmc_stats, bones_per_bundle),
    FIELD_ROW(mocap_vmc_stats, last_bundle_size),

    STRUCT_ROW(mocap_bvh_options),
    FIELD_ROW(mocap_bvh_options, struct_size),
    FIELD_ROW(mocap_bvh_options, rotation_order),
    FIELD_ROW(mocap_bvh_options, frame_rate),
    FIELD_ROW(mocap_bvh_options, flush_every),
};

const mocap_field_layout *mocap_struct_layout(uint32_t *count)
{
    if (count) *count = (uint32_t)(sizeof layout_table / sizeof layout_table[0]);
    return layout_table;
}
