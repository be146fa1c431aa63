// Output smoothing (src/pose/pose_filter.c): a one-euro filter per joint rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

extern "C" {
#include "mocap_math.h"
#include "pose_filter.h"
}

namespace {

const double kDt = 1.0 / 60.0;
const double kPi = 3.14159265358979323846;

pose_filter_params params(double min_cutoff = 1.0, double beta = 2.0)
{
    pose_filter_params p;
    p.dt = kDt;
    p.min_cutoff_hz = min_cutoff;
    p.beta = beta;
    p.speed_cutoff_hz = 1.0;
    p.trend_gain = 0.0;
    return p;
}

pose_filter_params with_trend(double min_cutoff, double beta, double trend = POSE_FILTER_TREND_GAIN)
{
    pose_filter_params p = params(min_cutoff, beta);
    p.trend_gain = trend;
    return p;
}

void about_y(double q[4], double angle)
{
    const double axis[3] = {0.0, 1.0, 0.0};
    quat_from_axis_angle(q, axis, angle);
}

// A joint at a fixed rotation with per-frame noise of about noise_deg (random axis).
void noisy(double out[4], const double truth[4], double noise_deg, std::mt19937 &rng)
{
    std::normal_distribution<double> n(0.0, noise_deg * kPi / 180.0 / std::sqrt(3.0));
    double aa[3] = {n(rng), n(rng), n(rng)};
    double angle = std::sqrt(aa[0] * aa[0] + aa[1] * aa[1] + aa[2] * aa[2]);
    double e[4];
    quat_from_axis_angle(e, aa, angle);
    quat_multiply(out, truth, e);
}

// Mean angle (deg) to the truth over frames [from, to) of a rotation about Y at `speed` rad/s
// with noise, and the mean frame-to-frame angle (deg) of the output.
struct FilterRun { double error_deg, step_deg; };
FilterRun run(const pose_filter_params &p, double speed, double noise_deg, int frames = 600, int from = 120)
{
    pose_filter_state s;
    pose_filter_reset(&s);
    std::mt19937 rng(7);
    double err = 0.0, step = 0.0, prev[4] = {1, 0, 0, 0};
    for (int t = 0; t < frames; ++t) {
        double truth[4], q[1][4];
        about_y(truth, speed * t * kDt);
        noisy(q[0], truth, noise_deg, rng);
        pose_filter_step(&s, &p, q, 1);
        if (t >= from) {
            err += quat_angle_deg(q[0], truth);
            step += quat_angle_deg(q[0], prev);
        }
        quat_copy(prev, q[0]);
    }
    return {err / (frames - from), step / (frames - from)};
}

}  // namespace

TEST(PoseFilter, DisabledPassesEveryRotationThrough)
{
    pose_filter_params p = params(0.0);
    pose_filter_state s;
    pose_filter_reset(&s);
    std::mt19937 rng(1);
    for (int t = 0; t < 50; ++t) {
        double truth[4], q[2][4], in[2][4];
        about_y(truth, 0.3 * t);
        noisy(in[0], truth, 5.0, rng);
        noisy(in[1], truth, 5.0, rng);
        std::copy(&in[0][0], &in[0][0] + 8, &q[0][0]);
        pose_filter_step(&s, &p, q, 2);
        for (int k = 0; k < 8; ++k) EXPECT_EQ((&q[0][0])[k], (&in[0][0])[k]);
    }
}

TEST(PoseFilter, FirstFrameAfterResetIsPassedThroughAndAConstantPoseStaysExact)
{
    pose_filter_params p = params();
    pose_filter_state s;
    pose_filter_reset(&s);
    double truth[4];
    about_y(truth, 1.2);
    for (int t = 0; t < 30; ++t) {
        double q[1][4];
        quat_copy(q[0], truth);
        pose_filter_step(&s, &p, q, 1);
        EXPECT_LT(quat_angle_deg(q[0], truth), 1e-6) << "frame " << t;
    }
    // after a reset the next input is taken as it is, however far from the old state
    pose_filter_reset(&s);
    double other[1][4], expect[4];
    about_y(expect, -2.0);
    quat_copy(other[0], expect);
    pose_filter_step(&s, &p, other, 1);
    EXPECT_LT(quat_angle_deg(other[0], expect), 1e-9);
}

TEST(PoseFilter, JitterAtRestIsRemoved)
{
    FilterRun raw = run(params(0.0), 0.0, 1.0);
    FilterRun filtered = run(params(), 0.0, 1.0);
    EXPECT_GT(raw.step_deg, 1.0);
    // frame-to-frame motion of a still joint: several times smaller, and closer to the truth
    EXPECT_LT(filtered.step_deg, raw.step_deg / 4.0);
    EXPECT_LT(filtered.error_deg, raw.error_deg * 0.7);
}

TEST(PoseFilter, FastMotionDoesNotLagLikeAFixedLowPass)
{
    // a 3 rad/s swing (172 deg/s), clean input: the error is the filter's lag
    FilterRun adaptive = run(params(1.0, 2.0), 3.0, 0.0);
    FilterRun fixed = run(params(1.0, 0.0), 3.0, 0.0);
    EXPECT_GT(fixed.error_deg, 20.0);         // 1 Hz low-pass: tau = 0.16 s behind -> ~27 deg
    EXPECT_LT(adaptive.error_deg, 5.0);       // cut-off rises to ~7 Hz: a few deg behind
    EXPECT_LT(adaptive.error_deg, fixed.error_deg / 5.0);
}

TEST(PoseFilter, OutputKeepsTheInputHemisphereAndUnitLength)
{
    pose_filter_params p = params();
    pose_filter_state s;
    pose_filter_reset(&s);
    std::mt19937 rng(3);
    for (int t = 0; t < 200; ++t) {
        double truth[4], q[1][4];
        about_y(truth, 0.05 * t);
        noisy(q[0], truth, 2.0, rng);
        if (t % 2) for (double &v : q[0]) v = -v;   // the same rotation, other sign
        double in[4];
        quat_copy(in, q[0]);
        pose_filter_step(&s, &p, q, 1);
        double dot = in[0] * q[0][0] + in[1] * q[0][1] + in[2] * q[0][2] + in[3] * q[0][3];
        EXPECT_GT(dot, 0.0) << "frame " << t;
        EXPECT_NEAR(quat_norm(q[0]), 1.0, 1e-9);
        EXPECT_LT(quat_angle_deg(q[0], truth), 10.0);
    }
}

TEST(PoseFilter, TheTrendFollowsASteadyTurnWithoutLag)
{
    // A clean 2 rad/s turn: the plain filter trails it, the trend catches up with it.
    FilterRun plain = run(params(2.0, 0.0), 2.0, 0.0);
    FilterRun trend = run(with_trend(2.0, 0.0), 2.0, 0.0);
    EXPECT_GT(plain.error_deg, 5.0);
    EXPECT_LT(trend.error_deg, 0.05);
    // and it still removes much of the jitter at rest (less than without the trend, which
    // reads some of the noise as turning)
    FilterRun raw = run(params(0.0), 0.0, 1.0);
    FilterRun still = run(with_trend(2.0, 12.0), 0.0, 1.0);
    EXPECT_LT(still.step_deg, raw.step_deg / 1.5);
    EXPECT_LT(still.error_deg, raw.error_deg);
}

TEST(PoseFilter, TheTrendStartsAtRestAfterAResetAndKeepsUnitQuaternions)
{
    pose_filter_params p = with_trend(2.0, 12.0);
    pose_filter_state s;
    pose_filter_reset(&s);
    std::mt19937 rng(5);
    for (int t = 0; t < 300; ++t) {
        double truth[4], q[1][4];
        about_y(truth, 3.0 * std::sin(0.02 * t));    // a swing that stops and turns back
        noisy(q[0], truth, 1.0, rng);
        pose_filter_step(&s, &p, q, 1);
        EXPECT_NEAR(quat_norm(q[0]), 1.0, 1e-9);
        EXPECT_LT(quat_angle_deg(q[0], truth), 8.0) << "frame " << t;
    }
    pose_filter_reset(&s);
    double still[1][4], expect[4];
    about_y(expect, 0.4);
    for (int t = 0; t < 20; ++t) {
        quat_copy(still[0], expect);
        pose_filter_step(&s, &p, still, 1);
        EXPECT_LT(quat_angle_deg(still[0], expect), 1e-6) << "frame " << t;   // no old velocity
    }
}
