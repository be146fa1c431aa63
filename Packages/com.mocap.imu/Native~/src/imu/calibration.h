/* Calibration maths (see docs/calibration.md):
 *   heading step: per sensor, world_to_model = A * Rz(-yaw), yaw = heading of the sensor's X axis
 *                 while it lies still pointing forward (A: Z-up world to Y-up model);
 *   T-pose step:  sensor_to_bone = world_to_model * R_world_sensor(T)  (bones are identity in the
 *                 T-pose), acceleration_offset = mean(world_to_model * f_world);
 *   every frame:  R_bone = world_to_model * R_world_sensor(t) * sensor_to_bone^T,
 *                 a_bone = world_to_model * f_world(t) - acceleration_offset.
 *   heading reset: per sensor, a yaw about model up so the bone's forward axis faces +Z again.
 * Nothing here depends on whether the sensor world is NWU or ENU, only on Z being up. */
#ifndef MOCAP_CALIBRATION_H
#define MOCAP_CALIBRATION_H

#include "frame_assembler.h"
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Thresholds for refusing a calibration window. */
#define CALIB_MAX_GYRO_RMS_DPS 10.0
#define CALIB_MAX_ORIENTATION_SPREAD_DEG 3.0
#define CALIB_MAX_ACCEL_NORM_ERROR 1.5      /* m/s^2: catches motion and g-vs-m/s^2 mix-ups */
#define CALIB_MAX_HEADING_TILT_DEG 30.0
#define CALIB_MIN_SAMPLE_FRACTION 0.5       /* of the frames in the window */

typedef struct calib_accumulator {
    int32_t step;          /* mocap_calibration_step; -1 when idle */
    int32_t state;         /* mocap_calibration_state */
    double start_t;        /* < 0: start at the first frame added */
    double duration;
    uint32_t frames;       /* frames seen inside the window */
    uint32_t sensor_count; /* the session's sensor set */
    int32_t segments[MOCAP_MAX_SENSORS];
    uint32_t optional_mask;/* sensors that may be missing from a window (left out, not refused) */
    uint32_t samples[MOCAP_MAX_SENSORS];
    double quat_sum[MOCAP_MAX_SENSORS][4];   /* sign-aligned sums for the mean orientation */
    double quat_first[MOCAP_MAX_SENSORS][4];
    double force_sum[MOCAP_MAX_SENSORS][3];
    double gyro_sq_sum[MOCAP_MAX_SENSORS];
    /* Orientation spread needs the mean first; the window's orientations are kept (fixed size). */
    uint32_t kept[MOCAP_MAX_SENSORS];
    float kept_quat[MOCAP_MAX_SENSORS][1024][4];
} calib_accumulator;

void calib_init(calib_accumulator *acc, uint32_t sensor_count, const int32_t *segments,
                uint32_t optional_mask);
/* Arm a step for the window [start_t, start_t + duration] (start_t < 0: from the next frame). */
void calib_begin(calib_accumulator *acc, int32_t step, double start_t, double duration);
/* Feed every output frame. Returns 1 when the window has just closed (call calib_finish). */
int calib_add_frame(calib_accumulator *acc, const raw_frame *frame);
/* Evaluate the window: on success updates cal (only the fields the step owns) and returns
 * MOCAP_OK; otherwise returns MOCAP_ERR_BAD_CALIBRATION with report->reason naming the sensors
 * and leaves cal untouched. report is always filled. mapping from the current calibration is
 * needed by HEADING_RESET. */
mocap_status calib_finish(calib_accumulator *acc, mocap_calibration *cal,
                          mocap_calibration_report *report);
/* Progress report while collecting (state, progress, seconds remaining). */
void calib_progress(const calib_accumulator *acc, double now_t, mocap_calibration_report *report);

/* Fill a calibration of these sensors (segments may be NULL for none) with identity mappings
 * and empty masks. */
void calib_identity(mocap_calibration *cal, uint32_t sensor_count, const int32_t *segments);
/* Fill out->sensors[*] and out->flags from a raw frame and a calibration in the session's sensor
 * order. world_frame (mocap_world_frame) picks the uncalibrated mapping for sensors without a
 * heading; optional_mask: sensors MOCAP_FRAME_CALIBRATED does not wait for. */
void calib_apply(const mocap_calibration *cal, int32_t world_frame, uint32_t optional_mask,
                 const raw_frame *in, mocap_frame *out);

/* Whether cal is a calibration the engine can use and write: a known sensor set, masks within it, a
 * heading for every fully calibrated sensor, rotation matrices, finite offsets. 0, or -1 with
 * the reason (naming the field) in why. */
int calib_check(const mocap_calibration *cal, char *why, size_t cap);
mocap_status calib_save(const mocap_calibration *cal, const char *path);
mocap_status calib_load(const char *path, mocap_calibration *out);

#ifdef __cplusplus
}
#endif
#endif
