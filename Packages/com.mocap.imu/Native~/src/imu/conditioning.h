/* Signal conditioning: device units to SI, quaternion validation, timestamp unwrapping and the
 * mapping of each sensor's clock onto the session (receive) clock. */
#ifndef MOCAP_CONDITIONING_H
#define MOCAP_CONDITIONING_H

#include <stdint.h>
#include "hipnuc_decoder.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A quaternion whose norm differs from 1 by more than this is rejected, not normalised. */
#define CONDITION_QUAT_NORM_TOLERANCE 0.02
/* Beyond any IMU's range (HiPNUC parts measure up to 16-32 g and 2000-4000 deg/s): a value
 * past these is a damaged sample, and finite-but-huge values would become Inf in float outputs. */
#define CONDITION_MAX_ACC_G 64.0
#define CONDITION_MAX_GYR_DPS 10000.0
#define CONDITION_MAX_EULER_DEG 3600.0

/* Why a sample was rejected (0 = accepted). */
enum {
    CONDITION_OK = 0,
    CONDITION_NOT_FINITE = 1,      /* NaN or Inf anywhere in the used fields */
    CONDITION_ZERO_QUATERNION = 2,
    CONDITION_NON_UNIT_QUATERNION = 3,
    CONDITION_NO_ORIENTATION = 4,  /* neither quaternion nor Euler angles present */
    CONDITION_OUT_OF_RANGE = 5     /* finite but beyond any sensor's range (see the limits) */
};

/* One sensor sample in SI units, on the session clock. */
typedef struct imu_sample {
    int32_t segment;         /* mocap_segment */
    uint32_t node_id;
    double t;                /* session clock, seconds */
    double quat[4];          /* sensor -> sensor world, unit */
    double acc[3];           /* specific force, sensor frame, m/s^2 */
    double force_world[3];   /* specific force in the sensor world frame (filled by pipeline) */
    double gyr[3];           /* angular rate, sensor frame, rad/s */
} imu_sample;

/* Convert a decoded sample to SI (acc g -> m/s^2 with 9.80665, deg/s -> rad/s), validate and
 * normalise its quaternion (from Euler angles when no quaternion was sent). Fills everything
 * except segment, t and force_world. Returns CONDITION_*. */
int condition_sample(const hipnuc_sample *in, imu_sample *out);

/* Unwraps the u32 millisecond counter: handles the 2^32 ms wrap and the 86,400,000 ms
 * time-of-day wrap of firmware that reports UTC time. */
typedef struct time_unwrapper {
    int initialised;
    uint32_t last_raw;
    int64_t offset_ms;  /* added to raw values */
} time_unwrapper;
void time_unwrapper_init(time_unwrapper *u);
int64_t time_unwrap_ms(time_unwrapper *u, uint32_t raw_ms);

/* Maps sensor time onto the receive clock: session_t = sensor_t + offset, with offset the
 * smallest (receive - sensor) seen recently, so transport latency jitter does not enter the
 * timeline. A jump of more than reset_after_s (sensor reboot, clock step) re-initialises.
 * A sample newer on the sensor clock always maps after the one before, at least
 * CLOCK_ORDER_STEP_S later: when the offset drops by more than the samples' spacing (data that
 * arrives faster than the sensor produced it: a backlog at start, a receiver catching up) the
 * samples of one read would otherwise all map to its receive time and all but one be refused
 * as not newer. Such a sample may then map up to CLOCK_ORDER_STEP_S per sample past its
 * receive time. */
#define CLOCK_ORDER_STEP_S 1e-4
typedef struct clock_mapper {
    int initialised;
    double offset;
    double reset_after_s;
    double drift_per_s;  /* how fast offset may rise to follow a sensor clock running slow */
    double last_receive;
    double last_sensor;  /* newest sensor time mapped, and where it went */
    double last_mapped;
} clock_mapper;
void clock_mapper_init(clock_mapper *c);
double clock_map(clock_mapper *c, double sensor_s, double receive_s);

#ifdef __cplusplus
}
#endif
#endif
