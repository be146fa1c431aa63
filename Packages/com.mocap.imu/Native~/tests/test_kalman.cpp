// Acceleration Kalman filter: noise reduction on body-like motion, bounded lag, tuning, dt cases.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

extern "C" {
#include "kalman.h"
#include "mocap_math.h"
}

namespace {

// Body-segment acceleration: energy falls with frequency as in human movement (the displacement
// spectrum falls faster than 1/f^2), so most of the amplitude sits below 1.5 Hz; the 3 Hz term is
// the fastest component a limb produces repeatedly. Each axis gets its own phases.
double body_accel(double t, int axis)
{
    const double amp[4] = {2.0, 1.0, 0.5, 0.25};
    const double freq[4] = {0.5, 1.2, 2.0, 3.0};
    double v = 0.0;
    for (int i = 0; i < 4; i++)
        v += amp[i] * std::sin(2.0 * MOCAP_PI * freq[i] * t + 0.7 * i + 1.3 * axis);
    return v;
}

struct Errors {
    double filtered_rms;   // filtered vs truth, noisy input
    double raw_rms;        // noisy input vs truth
    double clean_rms;      // filtered vs truth, noise-free input: the filter's lag alone
};

Errors run_body_motion(double q, double r, double sigma, uint64_t seed)
{
    accel_kalman noisy, clean;
    accel_kalman_init(&noisy, q, r);
    accel_kalman_init(&clean, q, r);
    mocap_rng rng;
    mocap_rng_seed(&rng, seed);
    double fe = 0, re = 0, ce = 0;
    int n = 0;
    for (int i = 0; i < 3000; i++) { // 30 s at 100 Hz
        double t = i * 0.01;
        double truth[3], z[3], out[3], out_clean[3];
        for (int a = 0; a < 3; a++) {
            truth[a] = body_accel(t, a);
            z[a] = truth[a] + sigma * mocap_rng_gaussian(&rng);
        }
        accel_kalman_update(&noisy, t, z, out);
        accel_kalman_update(&clean, t, truth, out_clean);
        if (i < 100) // let the start-up transient pass
            continue;
        for (int a = 0; a < 3; a++) {
            fe += (out[a] - truth[a]) * (out[a] - truth[a]);
            re += (z[a] - truth[a]) * (z[a] - truth[a]);
            ce += (out_clean[a] - truth[a]) * (out_clean[a] - truth[a]);
            n++;
        }
    }
    return {std::sqrt(fe / n), std::sqrt(re / n), std::sqrt(ce / n)};
}

} // namespace

// The defaults: r is the variance of the test noise (0.2 m/s^2, the order of accelerometer noise
// plus strap and soft-tissue vibration on a limb), q was picked by sweeping it on this signal
// (measured ratio ~0.64 at q = 1000; 0.74 at q = 200 and 0.70 at q = 5000): the 2-state model
// cannot do much better without lag, and the lag at the default stays a few percent of the signal.
TEST(Kalman, DefaultsReduceNoiseOnBodyMotionWithBoundedLag)
{
    for (uint64_t seed : {1u, 2u, 3u}) {
        Errors e = run_body_motion(KALMAN_DEFAULT_PROCESS_NOISE, KALMAN_DEFAULT_MEASUREMENT_NOISE,
                                   0.2, seed);
        EXPECT_NEAR(e.raw_rms, 0.2, 0.01);
        EXPECT_LT(e.filtered_rms, 0.7 * e.raw_rms) << "seed " << seed;
        // Signal RMS is ~1.7 m/s^2; the clean-signal error is the lag/overshoot of the model.
        EXPECT_LT(e.clean_rms, 0.06) << "seed " << seed;
    }
}

TEST(Kalman, DefaultProcessNoiseBeatsTenTimesSmallerAndLarger)
{
    const double q = KALMAN_DEFAULT_PROCESS_NOISE, r = KALMAN_DEFAULT_MEASUREMENT_NOISE;
    Errors def = run_body_motion(q, r, 0.2, 9);
    Errors low = run_body_motion(q / 10, r, 0.2, 9);   // too smooth: lags
    Errors high = run_body_motion(q * 10, r, 0.2, 9);  // too nervous: passes noise
    EXPECT_LT(def.filtered_rms, low.filtered_rms);
    EXPECT_LT(def.filtered_rms, high.filtered_rms);
    EXPECT_GT(low.clean_rms, def.clean_rms); // the lower q's loss is lag
}

TEST(Kalman, LargerMeasurementNoiseGivesSmootherOutput)
{
    auto output_variance = [](double r) {
        accel_kalman k;
        accel_kalman_init(&k, KALMAN_DEFAULT_PROCESS_NOISE, r);
        mocap_rng rng;
        mocap_rng_seed(&rng, 77);
        double sum = 0, sq = 0;
        int n = 0;
        for (int i = 0; i < 2000; i++) {
            double z[3], out[3];
            for (int a = 0; a < 3; a++)
                z[a] = 9.81 * (a == 2) + 0.2 * mocap_rng_gaussian(&rng);
            accel_kalman_update(&k, i * 0.01, z, out);
            if (i >= 200) {
                sum += out[2];
                sq += out[2] * out[2];
                n++;
            }
        }
        double mean = sum / n;
        EXPECT_NEAR(mean, 9.81, 0.05); // no bias
        return sq / n - mean * mean;
    };
    double v_small = output_variance(0.01);
    double v_default = output_variance(0.04);
    double v_large = output_variance(1.0);
    EXPECT_LT(v_default, v_small);
    EXPECT_LT(v_large, 0.7 * v_default); // measured ~0.52
    EXPECT_LT(v_default, 0.04); // below the input variance
}

TEST(Kalman, FirstMeasurementInitialises)
{
    accel_kalman k;
    accel_kalman_init(&k, KALMAN_DEFAULT_PROCESS_NOISE, KALMAN_DEFAULT_MEASUREMENT_NOISE);
    const double z[3] = {1.5, -2.0, 9.8};
    double out[3];
    accel_kalman_update(&k, 12.34, z, out);
    for (int a = 0; a < 3; a++)
        EXPECT_DOUBLE_EQ(out[a], z[a]);
    EXPECT_EQ(k.initialised, 1);
    // Reset forgets everything: a new first measurement is passed straight through.
    accel_kalman_reset(&k);
    const double z2[3] = {-4, 4, 0};
    accel_kalman_update(&k, 13.0, z2, out);
    for (int a = 0; a < 3; a++)
        EXPECT_DOUBLE_EQ(out[a], z2[a]);
}

TEST(Kalman, IrregularIntervalsTrackARampWithoutBias)
{
    // A linear ramp is exactly the model's constant-rate case: after convergence the estimate
    // must sit on it whatever the sample spacing.
    accel_kalman k;
    accel_kalman_init(&k, KALMAN_DEFAULT_PROCESS_NOISE, KALMAN_DEFAULT_MEASUREMENT_NOISE);
    mocap_rng rng;
    mocap_rng_seed(&rng, 5);
    double t = 0;
    double out[3];
    for (int i = 0; i < 500; i++) {
        t += 0.002 + 0.03 * mocap_rng_uniform(&rng); // 2..32 ms, like a lossy radio link
        const double z[3] = {3.0 * t, -1.0 * t + 2.0, 9.81};
        accel_kalman_update(&k, t, z, out);
        if (i > 50) {
            EXPECT_NEAR(out[0], 3.0 * t, 1e-3);
            EXPECT_NEAR(out[1], -1.0 * t + 2.0, 1e-3);
            EXPECT_NEAR(out[2], 9.81, 1e-6);
        }
    }
}

TEST(Kalman, NonPositiveIntervalIsMeasurementUpdateOnly)
{
    accel_kalman k;
    accel_kalman_init(&k, KALMAN_DEFAULT_PROCESS_NOISE, KALMAN_DEFAULT_MEASUREMENT_NOISE);
    double out[3];
    for (int i = 0; i < 100; i++) {
        const double z[3] = {1, 1, 1};
        accel_kalman_update(&k, i * 0.01, z, out);
    }
    double last_t = k.last_t;
    double p00 = k.axis[0].p[0][0];
    // Same timestamp again and an older one: no prediction, so the variance can only shrink and
    // the clock does not move backwards.
    const double z[3] = {2, 2, 2};
    accel_kalman_update(&k, last_t, z, out);
    EXPECT_GT(out[0], 1.0);
    EXPECT_LT(out[0], 2.0);
    EXPECT_LE(k.axis[0].p[0][0], p00);
    accel_kalman_update(&k, last_t - 0.5, z, out);
    EXPECT_DOUBLE_EQ(k.last_t, last_t);
    EXPECT_TRUE(std::isfinite(out[0]));
    EXPECT_LE(out[0], 2.0);
}

TEST(Kalman, LongGapRestartsInsteadOfExtrapolating)
{
    accel_kalman k;
    accel_kalman_init(&k, KALMAN_DEFAULT_PROCESS_NOISE, KALMAN_DEFAULT_MEASUREMENT_NOISE);
    double out[3];
    for (int i = 0; i < 100; i++) { // a steep ramp builds up a large rate estimate
        const double z[3] = {20.0 * i * 0.01, 0, 0};
        accel_kalman_update(&k, i * 0.01, z, out);
    }
    const double z[3] = {0.5, 0.5, 0.5};
    accel_kalman_update(&k, 10.0, z, out); // 9 s later (sensor was out of range)
    for (int a = 0; a < 3; a++)
        EXPECT_DOUBLE_EQ(out[a], z[a]);
}

TEST(Kalman, NonFiniteMeasurementDoesNotPoisonState)
{
    accel_kalman k;
    accel_kalman_init(&k, KALMAN_DEFAULT_PROCESS_NOISE, KALMAN_DEFAULT_MEASUREMENT_NOISE);
    double out[3];
    const double z[3] = {1, 2, 3};
    for (int i = 0; i < 10; i++)
        accel_kalman_update(&k, i * 0.01, z, out);
    const double bad[3] = {NAN, 2, 3};
    accel_kalman_update(&k, 0.1, bad, out);
    EXPECT_TRUE(std::isfinite(out[0]));
    accel_kalman_update(&k, 0.11, z, out);
    for (int a = 0; a < 3; a++)
        EXPECT_NEAR(out[a], z[a], 1e-6);
}

TEST(Kalman, InvalidParametersFallBackToDefaults)
{
    accel_kalman k;
    accel_kalman_init(&k, -1.0, NAN);
    EXPECT_DOUBLE_EQ(k.process_noise, KALMAN_DEFAULT_PROCESS_NOISE);
    EXPECT_DOUBLE_EQ(k.measurement_noise, KALMAN_DEFAULT_MEASUREMENT_NOISE);
}
