// Signal conditioning: units, sample validation, timestamp unwrapping, clock mapping.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

extern "C" {
#include "conditioning.h"
#include "mocap_math.h"
}

namespace {

hipnuc_sample quat_sample()
{
    hipnuc_sample s;
    std::memset(&s, 0, sizeof s);
    s.fields = HIPNUC_FIELD_NODE_ID | HIPNUC_FIELD_TIME | HIPNUC_FIELD_ACC | HIPNUC_FIELD_GYR |
               HIPNUC_FIELD_QUAT | HIPNUC_FIELD_EULER | HIPNUC_FIELD_MAG;
    s.node_id = 3;
    s.quat[0] = 1.0f;
    s.acc_g[2] = 1.0f;
    return s;
}

} // namespace

TEST(Conditioning, ConvertsUnitsToSI)
{
    hipnuc_sample in = quat_sample();
    in.acc_g[0] = 0.5f;
    in.acc_g[1] = -2.0f;
    in.gyr_dps[0] = 180.0f;
    in.gyr_dps[1] = -90.0f;
    in.gyr_dps[2] = 1.0f;
    imu_sample out;
    ASSERT_EQ(condition_sample(&in, &out), CONDITION_OK);
    EXPECT_EQ(out.node_id, 3u);
    EXPECT_NEAR(out.acc[0], 0.5 * 9.80665, 1e-6);
    EXPECT_NEAR(out.acc[1], -2.0 * 9.80665, 1e-6);
    EXPECT_NEAR(out.acc[2], 9.80665, 1e-6);
    EXPECT_NEAR(out.gyr[0], MOCAP_PI, 1e-6);
    EXPECT_NEAR(out.gyr[1], -MOCAP_PI / 2, 1e-6);
    EXPECT_NEAR(out.gyr[2], MOCAP_PI / 180, 1e-8);
}

TEST(Conditioning, RejectsNonFiniteUsedFieldsOnly)
{
    imu_sample out;
    hipnuc_sample in = quat_sample();
    in.acc_g[1] = NAN;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NOT_FINITE);
    in = quat_sample();
    in.gyr_dps[2] = INFINITY;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NOT_FINITE);
    in = quat_sample();
    in.quat[3] = NAN;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NOT_FINITE);
    // Fields that are not used do not matter: the magnetometer, the Euler angles when a
    // quaternion is present, and values whose field bit is clear.
    in = quat_sample();
    in.mag_ut[0] = NAN;
    in.euler_deg[0] = NAN;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OK);
    in = quat_sample();
    in.fields &= ~(uint32_t)HIPNUC_FIELD_ACC;
    in.acc_g[0] = NAN;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OK);
    // Euler-only sample with a NaN angle.
    in = quat_sample();
    in.fields &= ~(uint32_t)HIPNUC_FIELD_QUAT;
    in.euler_deg[2] = -INFINITY;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NOT_FINITE);
}

// Finite but beyond any sensor's range: a damaged sample, refused before 1e38 g turns into
// infinity in the float outputs or spikes the Kalman filter for many samples.
TEST(Conditioning, RejectsValuesBeyondAnySensorsRange)
{
    imu_sample out;
    hipnuc_sample in = quat_sample();
    in.acc_g[0] = 1e38f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OUT_OF_RANGE);
    in = quat_sample();
    in.acc_g[2] = -65.0f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OUT_OF_RANGE);
    in = quat_sample();
    in.gyr_dps[1] = 12000.0f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OUT_OF_RANGE);
    in = quat_sample();
    in.fields &= ~(uint32_t)HIPNUC_FIELD_QUAT;
    in.euler_deg[0] = 1e20f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OUT_OF_RANGE);
    // A hard impact (32 g) and a fast spin (4000 deg/s) are real and pass.
    in = quat_sample();
    in.acc_g[0] = 32.0f;
    in.gyr_dps[2] = -4000.0f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OK);
    // Fields that are not used still do not matter.
    in = quat_sample();
    in.euler_deg[0] = 1e30f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_OK);
}

TEST(Conditioning, QuaternionValidationAndNormalisation)
{
    imu_sample out;
    hipnuc_sample in = quat_sample();
    in.quat[0] = 0.0f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_ZERO_QUATERNION);

    // Norm 1.05: beyond the tolerance, a corrupt value rather than rounding.
    in = quat_sample();
    in.quat[0] = 0.6f * 1.05f;
    in.quat[1] = 0.8f * 1.05f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NON_UNIT_QUATERNION);
    in.quat[0] = 0.6f * 0.95f;
    in.quat[1] = 0.8f * 0.95f;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NON_UNIT_QUATERNION);

    // Norm 1.01: accepted and normalised, direction kept.
    in.quat[0] = 0.6f * 1.01f;
    in.quat[1] = 0.8f * 1.01f;
    ASSERT_EQ(condition_sample(&in, &out), CONDITION_OK);
    EXPECT_NEAR(quat_norm(out.quat), 1.0, 1e-12);
    EXPECT_NEAR(out.quat[0], 0.6, 1e-6);
    EXPECT_NEAR(out.quat[1], 0.8, 1e-6);
}

TEST(Conditioning, EulerUsedWhenNoQuaternion)
{
    hipnuc_sample in = quat_sample();
    in.fields &= ~(uint32_t)HIPNUC_FIELD_QUAT;
    in.quat[0] = 0.0f; // would be rejected if it were used
    in.euler_deg[0] = 30.0f;  // roll about X
    in.euler_deg[1] = -20.0f; // pitch about Y
    in.euler_deg[2] = 75.0f;  // yaw about Z
    imu_sample out;
    ASSERT_EQ(condition_sample(&in, &out), CONDITION_OK);
    double m[9], rx[9], ry[9], rz[9], r[9];
    quat_to_mat3(m, out.quat);
    mat3_rotation_x(rx, 30 * MOCAP_DEG2RAD);
    mat3_rotation_y(ry, -20 * MOCAP_DEG2RAD);
    mat3_rotation_z(rz, 75 * MOCAP_DEG2RAD);
    mat3_multiply(r, ry, rx);
    mat3_multiply(r, rz, r); // R = Rz(yaw) Ry(pitch) Rx(roll)
    for (int i = 0; i < 9; i++)
        EXPECT_NEAR(m[i], r[i], 1e-6);

    // Pure yaw 90: the sensor's X axis points along world Y.
    in.euler_deg[0] = in.euler_deg[1] = 0.0f;
    in.euler_deg[2] = 90.0f;
    ASSERT_EQ(condition_sample(&in, &out), CONDITION_OK);
    const double x[3] = {1, 0, 0};
    double v[3];
    quat_rotate(v, out.quat, x);
    EXPECT_NEAR(v[1], 1.0, 1e-6);
}

TEST(Conditioning, NoOrientationRejectedMissingVectorsZeroed)
{
    hipnuc_sample in = quat_sample();
    in.fields &= ~(uint32_t)(HIPNUC_FIELD_QUAT | HIPNUC_FIELD_EULER);
    imu_sample out;
    EXPECT_EQ(condition_sample(&in, &out), CONDITION_NO_ORIENTATION);

    in = quat_sample();
    in.fields = HIPNUC_FIELD_QUAT; // a bare 0xD1 item
    in.acc_g[2] = 5.0f;
    in.gyr_dps[0] = 5.0f;
    std::memset(&out, 0x7f, sizeof out);
    ASSERT_EQ(condition_sample(&in, &out), CONDITION_OK);
    for (int i = 0; i < 3; i++) {
        EXPECT_EQ(out.acc[i], 0.0);
        EXPECT_EQ(out.gyr[i], 0.0);
    }
}

TEST(TimeUnwrap, ThroughThe32BitWrap)
{
    time_unwrapper u;
    time_unwrapper_init(&u);
    int64_t expect = 4294967296LL - 20;
    EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)expect), expect);
    for (int i = 0; i < 10; i++) {
        expect += 5;
        EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)(expect & 0xffffffffLL)), expect);
    }
    EXPECT_GT(expect, 4294967296LL);
    // A dropout of a few seconds across the wrap is still unwrapped.
    expect += 4000;
    EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)(expect & 0xffffffffLL)), expect);
}

TEST(TimeUnwrap, ThroughTheTimeOfDayWrapTwice)
{
    time_unwrapper u;
    time_unwrapper_init(&u);
    const int64_t day = 86400000LL;
    int64_t t = day - 30;
    EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)t), t);
    for (int i = 0; i < 20; i++) {
        t += 10;
        EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)(t % day)), t);
    }
    t = 2 * day - 5;
    EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)(t % day)), t);
    t += 10;
    EXPECT_EQ(time_unwrap_ms(&u, (uint32_t)(t % day)), t);
    EXPECT_GE(t, 2 * day);
}

TEST(TimeUnwrap, SmallBackwardStepsAndRebootsAreNotWraps)
{
    time_unwrapper u;
    time_unwrapper_init(&u);
    EXPECT_EQ(time_unwrap_ms(&u, 100000), 100000);
    EXPECT_EQ(time_unwrap_ms(&u, 99990), 99990); // late packet: raw value kept
    EXPECT_EQ(time_unwrap_ms(&u, 100010), 100010);

    // Reboot at mid-day (uptime counter restarting): not "most of a day" backwards.
    time_unwrapper_init(&u);
    EXPECT_EQ(time_unwrap_ms(&u, 50000000), 50000000);
    EXPECT_EQ(time_unwrap_ms(&u, 10), 10);
    EXPECT_EQ(time_unwrap_ms(&u, 20), 20);

    // Reboot long after the day mark on a u32 uptime counter: not a 2^32 wrap either.
    time_unwrapper_init(&u);
    EXPECT_EQ(time_unwrap_ms(&u, 3000000000u), 3000000000LL);
    EXPECT_EQ(time_unwrap_ms(&u, 5), 5);
}

namespace {

// Sample n of a 100 Hz sensor: true time on the session clock, the sensor's own clock reading
// and the receive time after a latency of at least min_latency.
struct Stream {
    double true_t, sensor_t, receive_t;
};

} // namespace

TEST(ClockMap, JitteryLatencyTracksTrueSampleTimes)
{
    clock_mapper c;
    clock_mapper_init(&c);
    mocap_rng rng;
    mocap_rng_seed(&rng, 99);
    const double min_latency = 0.004, sensor_epoch = -1234.5;
    double worst_raw = 0, worst_mapped_after_settle = 0, worst_interval_err = 0;
    double prev_mapped = 0;
    for (int i = 0; i < 3000; i++) {
        double true_t = 10.0 + i * 0.01;
        double sensor_t = true_t + sensor_epoch;
        // USB/radio latency: a floor plus up to 25 ms of jitter, occasionally bursts of 60 ms.
        double jitter = 0.025 * mocap_rng_uniform(&rng);
        if (mocap_rng_uniform(&rng) < 0.02)
            jitter += 0.06;
        double receive_t = true_t + min_latency + jitter;
        double mapped = clock_map(&c, sensor_t, receive_t);
        EXPECT_LE(mapped, receive_t + 1e-12); // never in the future
        worst_raw = std::fmax(worst_raw, std::fabs(receive_t - true_t - min_latency));
        if (i >= 50) {
            // After the first half second the estimate sits near the latency floor: the mapped
            // time is the true time plus the minimum latency, give or take the upward drift
            // allowance (10 us per sample) accumulated until the next near-floor delivery.
            worst_mapped_after_settle =
                std::fmax(worst_mapped_after_settle, std::fabs(mapped - true_t - min_latency));
            worst_interval_err = std::fmax(worst_interval_err, std::fabs(mapped - prev_mapped - 0.01));
        }
        prev_mapped = mapped;
    }
    EXPECT_GT(worst_raw, 0.05); // the input really was jittery
    EXPECT_LT(worst_mapped_after_settle, 0.003); // vs 85 ms of raw jitter
    EXPECT_LT(worst_interval_err, 0.003);
}

TEST(ClockMap, SlowAndFastSensorClocksDoNotStallOrReset)
{
    for (double ppm : {-300.0, 300.0}) {
        clock_mapper c;
        clock_mapper_init(&c);
        mocap_rng rng;
        mocap_rng_seed(&rng, 4);
        double worst = 0, prev = -1e9;
        bool monotonic = true;
        for (int i = 0; i < 60000; i++) { // 10 minutes at 100 Hz
            double true_t = i * 0.01;
            double sensor_t = 500.0 + true_t * (1.0 + ppm * 1e-6);
            double receive_t = true_t + 0.003 + 0.02 * mocap_rng_uniform(&rng);
            double mapped = clock_map(&c, sensor_t, receive_t);
            if (i > 100)
                worst = std::fmax(worst, std::fabs(mapped - true_t - 0.003));
            monotonic = monotonic && mapped > prev;
            prev = mapped;
        }
        // 300 ppm over 10 minutes is 180 ms of clock drift; the mapping absorbs it.
        EXPECT_LT(worst, 0.003) << "ppm " << ppm;
        EXPECT_TRUE(monotonic) << "ppm " << ppm;
    }
}

// A backlog at the start, or a receiver catching up after a radio gap, delivers samples faster
// than the sensor made them: several per read, sharing the read's receive time, while the
// latency estimate falls with every sample. Each must still map after the one before.
TEST(ClockMap, DataFasterThanTheSensorMadeItStaysInOrder)
{
    clock_mapper c;
    clock_mapper_init(&c);
    double prev = -1e9;
    int out_of_order = 0, past_receive = 0;
    double worst_lead = 0;
    for (int read = 0; read < 50; read++) {
        const double receive_t = 20.0 + read * 0.02; // 10 samples of 10 ms every 20 ms: 5x
        for (int k = 0; k < 10; k++) {
            const double sensor_t = 300.0 + (read * 10 + k) * 0.01;
            const double mapped = clock_map(&c, sensor_t, receive_t);
            if (!(mapped >= prev + CLOCK_ORDER_STEP_S - 1e-12)) out_of_order++;
            if (mapped > receive_t) past_receive++;
            worst_lead = std::fmax(worst_lead, mapped - receive_t);
            prev = mapped;
        }
    }
    EXPECT_EQ(out_of_order, 0);
    EXPECT_GT(past_receive, 0);                               // the case really arose
    EXPECT_LE(worst_lead, 10 * CLOCK_ORDER_STEP_S + 1e-9);    // one step per sample of a read
    // A repeated sensor time is not moved: the caller refuses it as not newer.
    const double again = clock_map(&c, 300.0 + 499 * 0.01, 21.0);
    EXPECT_LE(again, prev);
}

TEST(ClockMap, SensorRebootReinitialises)
{
    clock_mapper c;
    clock_mapper_init(&c);
    double mapped = 0;
    for (int i = 0; i < 500; i++) {
        double true_t = 100.0 + i * 0.01;
        mapped = clock_map(&c, 7000.0 + i * 0.01, true_t + 0.005);
    }
    EXPECT_NEAR(mapped, 100.0 + 499 * 0.01 + 0.005, 1e-9);
    // The sensor reboots: its clock restarts at 0 while the session clock goes on.
    for (int i = 0; i < 200; i++) {
        double true_t = 110.0 + i * 0.01;
        mapped = clock_map(&c, i * 0.01, true_t + 0.005);
        EXPECT_NEAR(mapped, true_t + 0.005, 1e-9) << "sample " << i << " after the reboot";
    }
    // A clock step forwards (firmware sets its time) also re-initialises.
    mapped = clock_map(&c, 1e6, 112.0 + 0.005);
    EXPECT_NEAR(mapped, 112.005, 1e-9);
}
