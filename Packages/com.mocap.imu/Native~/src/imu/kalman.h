/* Kalman filter on a 3-axis acceleration signal (one filter per sensor). Each axis is an
 * independent constant-jerk model: state (a, da/dt), measurement a. Handles irregular sample
 * intervals; the first measurement initialises the state. */
#ifndef MOCAP_KALMAN_H
#define MOCAP_KALMAN_H

#ifdef __cplusplus
extern "C" {
#endif

/* Defaults, tuned on synthetic body motion sampled at 100 Hz (see tests/test_kalman.cpp). */
#define KALMAN_DEFAULT_PROCESS_NOISE 1000.0   /* jerk-rate spectral density, (m/s^3)^2 / s */
#define KALMAN_DEFAULT_MEASUREMENT_NOISE 0.04 /* accelerometer noise variance, (m/s^2)^2 */

typedef struct kalman_axis {
    double x[2];       /* value, rate */
    double p[2][2];    /* covariance */
} kalman_axis;

typedef struct accel_kalman {
    double process_noise;
    double measurement_noise;
    double last_t;
    int initialised;
    kalman_axis axis[3];
} accel_kalman;

void accel_kalman_init(accel_kalman *k, double process_noise, double measurement_noise);
void accel_kalman_reset(accel_kalman *k);
/* Fold in measurement z taken at time t (seconds, non-decreasing); writes the estimate. */
void accel_kalman_update(accel_kalman *k, double t, const double z[3], double out[3]);

#ifdef __cplusplus
}
#endif
#endif
