/* Per-axis two-state Kalman filter (value, rate) for the world-frame specific force. The process
 * model is the continuous white-noise model on the second derivative, discretised exactly for
 * each (irregular) interval, so sample-rate changes and dropouts need no retuning. */
#include "kalman.h"

#include <math.h>
#include <string.h>

/* After a gap this long the old state says nothing useful about the signal (body motion
 * decorrelates within a few hundred ms) and extrapolating the rate across it only adds error:
 * restart from the next measurement instead. */
#define KALMAN_MAX_GAP_S 0.5

/* Initial rate variance: the rate is unknown at start; this is "very large" next to any body
 * motion ((m/s^3)^2) without making the covariance arithmetic ill-conditioned. */
#define KALMAN_INITIAL_RATE_VARIANCE 1.0e6

void accel_kalman_init(accel_kalman *k, double process_noise, double measurement_noise)
{
    memset(k, 0, sizeof *k);
    k->process_noise =
        (process_noise > 0.0 && isfinite(process_noise)) ? process_noise : KALMAN_DEFAULT_PROCESS_NOISE;
    k->measurement_noise = (measurement_noise > 0.0 && isfinite(measurement_noise))
                               ? measurement_noise
                               : KALMAN_DEFAULT_MEASUREMENT_NOISE;
    accel_kalman_reset(k);
}

void accel_kalman_reset(accel_kalman *k)
{
    k->initialised = 0;
    k->last_t = 0.0;
    memset(k->axis, 0, sizeof k->axis);
}

static void axis_start(kalman_axis *a, double z, double r)
{
    a->x[0] = z;
    a->x[1] = 0.0;
    a->p[0][0] = r;
    a->p[0][1] = a->p[1][0] = 0.0;
    a->p[1][1] = KALMAN_INITIAL_RATE_VARIANCE;
}

static void axis_predict(kalman_axis *a, double dt, double q)
{
    /* F = [[1, dt], [0, 1]]; P' = F P F^T + Q. */
    double p00 = a->p[0][0], p01 = a->p[0][1], p10 = a->p[1][0], p11 = a->p[1][1];
    double dt2 = dt * dt;
    a->x[0] += dt * a->x[1];
    double n00 = p00 + dt * (p10 + p01) + dt2 * p11 + q * dt2 * dt / 3.0;
    double n01 = p01 + dt * p11 + q * dt2 / 2.0;
    double n10 = p10 + dt * p11 + q * dt2 / 2.0;
    double n11 = p11 + q * dt;
    a->p[0][0] = n00;
    /* Symmetrise: rounding would otherwise let the two off-diagonal terms wander apart. */
    a->p[0][1] = a->p[1][0] = 0.5 * (n01 + n10);
    a->p[1][1] = n11;
}

static void axis_update(kalman_axis *a, double z, double r)
{
    /* H = [1, 0]. */
    double s = a->p[0][0] + r;
    double k0 = a->p[0][0] / s;
    double k1 = a->p[1][0] / s;
    double innovation = z - a->x[0];
    a->x[0] += k0 * innovation;
    a->x[1] += k1 * innovation;
    double p00 = a->p[0][0], p01 = a->p[0][1], p11 = a->p[1][1];
    a->p[0][0] = (1.0 - k0) * p00;
    a->p[0][1] = a->p[1][0] = (1.0 - k0) * p01;
    a->p[1][1] = p11 - k1 * p01;
}

void accel_kalman_update(accel_kalman *k, double t, const double z[3], double out[3])
{
    int finite = isfinite(t) && isfinite(z[0]) && isfinite(z[1]) && isfinite(z[2]);
    if (!finite) {
        /* A bad measurement must not poison the state: report the current estimate (or the
         * input when there is none) and keep going. */
        for (int i = 0; i < 3; i++)
            out[i] = k->initialised ? k->axis[i].x[0] : z[i];
        return;
    }
    double dt = t - k->last_t;
    if (!k->initialised || dt > KALMAN_MAX_GAP_S) {
        for (int i = 0; i < 3; i++) {
            axis_start(&k->axis[i], z[i], k->measurement_noise);
            out[i] = z[i];
        }
        k->initialised = 1;
        k->last_t = t;
        return;
    }
    for (int i = 0; i < 3; i++) {
        /* dt <= 0 (a repeated or out-of-order stamp): no time passed as far as the model knows,
         * so the measurement is simply folded in. */
        if (dt > 0.0)
            axis_predict(&k->axis[i], dt, k->process_noise);
        axis_update(&k->axis[i], z[i], k->measurement_noise);
        out[i] = k->axis[i].x[0];
    }
    if (dt > 0.0)
        k->last_t = t;
}
