// The pose guard (src/pose/pose_limits.c) on the engine's range table: poses people take pass
// unchanged, a joint bent where nobody's bends is turned back to the tolerance, and the answer
// does not depend on what the guard remembered from the frame before.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

extern "C" {
#include "pose_limits.h"
#include "pose_range_table.h"
}

namespace {

const double kTolerance = 25.0;
const int kLeftKnee = 4, kRightElbow = 19, kHead = 15;

void table_point(int joint, uint32_t k, double q[4])
{
    const int8_t *v = pose_range_points[pose_range_joints[joint].first + k];
    double n = 0.0;
    for (int i = 0; i < 4; ++i) n += double(v[i]) * v[i];
    for (int i = 0; i < 4; ++i) q[i] = v[i] / std::sqrt(n);
}

double rotation_between_deg(const double a[4], const double b[4])
{
    const double d = std::fabs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
    return 2.0 * std::acos(std::fmin(1.0, d)) * 180.0 / M_PI;
}

// q turned by angle_deg about the unit axis (x, y, z), on the right (in the joint's own frame).
void turn(double q[4], double angle_deg, double x, double y, double z)
{
    const double h = angle_deg * M_PI / 360.0, s = std::sin(h);
    const double r[4] = {std::cos(h), x * s, y * s, z * s};
    const double o[4] = {q[0] * r[0] - q[1] * r[1] - q[2] * r[2] - q[3] * r[3],
                         q[0] * r[1] + q[1] * r[0] + q[2] * r[3] - q[3] * r[2],
                         q[0] * r[2] - q[1] * r[3] + q[2] * r[0] + q[3] * r[1],
                         q[0] * r[3] + q[1] * r[2] - q[2] * r[1] + q[3] * r[0]};
    std::memcpy(q, o, sizeof o);
}

// Every guarded joint at a rotation of its own range; the root at an arbitrary orientation.
void pose_in_range(double q[POSE_LIMITS_JOINTS][4])
{
    for (int j = 0; j < POSE_LIMITS_JOINTS; ++j) {
        if (pose_range_joints[j].count == 0) {
            q[j][0] = 0.5; q[j][1] = 0.5; q[j][2] = -0.5; q[j][3] = 0.5;
        } else {
            table_point(j, pose_range_joints[j].count / 2, q[j]);
        }
    }
}

}  // namespace

TEST(PoseLimits, TheTableCoversEveryJointButTheRoot)
{
    EXPECT_EQ(pose_range_joints[0].count, 0u);
    uint32_t next = 0;
    for (int j = 0; j < POSE_RANGE_JOINTS; ++j) {
        EXPECT_EQ(pose_range_joints[j].first, next) << "joint " << j;
        if (j > 0) {
            EXPECT_GT(pose_range_joints[j].count, 0u) << "joint " << j;
        }
        next += pose_range_joints[j].count;
    }
    // A knee bends one way: its range is far narrower than a shoulder's.
    EXPECT_LT(pose_range_joints[kLeftKnee].count * 3, pose_range_joints[16].count);
}

TEST(PoseLimits, APoseInTheRangePassesBitForBit)
{
    double q[POSE_LIMITS_JOINTS][4], before[POSE_LIMITS_JOINTS][4];
    pose_in_range(q);
    // A little off its point still counts as in range.
    turn(q[kHead], 10.0, 0.0, 0.0, 1.0);
    std::memcpy(before, q, sizeof q);
    pose_limits_state s;
    pose_limits_reset(&s);
    uint8_t moved[POSE_LIMITS_JOINTS];
    EXPECT_EQ(pose_limits_apply(&s, kTolerance, q, moved), 0);
    EXPECT_EQ(std::memcmp(q, before, sizeof q), 0);
    for (int j = 0; j < POSE_LIMITS_JOINTS; ++j) EXPECT_EQ(moved[j], 0) << "joint " << j;
}

TEST(PoseLimits, AKneeBentSidewaysIsTurnedBackToTheTolerance)
{
    double q[POSE_LIMITS_JOINTS][4];
    pose_in_range(q);
    double bent[4];
    std::memcpy(bent, q[kLeftKnee], sizeof bent);
    turn(bent, 120.0, 0.0, 0.0, 1.0);   // about the forward axis: no knee bends so
    const double was = pose_limits_distance_deg(kLeftKnee, bent);
    ASSERT_GT(was, kTolerance + 10.0);
    std::memcpy(q[kLeftKnee], bent, sizeof bent);
    double root[4];
    std::memcpy(root, q[0], sizeof root);

    pose_limits_state s;
    pose_limits_reset(&s);
    uint8_t moved[POSE_LIMITS_JOINTS];
    EXPECT_EQ(pose_limits_apply(&s, kTolerance, q, moved), 1);
    EXPECT_EQ(moved[kLeftKnee], 1);
    EXPECT_EQ(std::memcmp(q[0], root, sizeof root), 0) << "the root is never guarded";
    EXPECT_NEAR(pose_limits_distance_deg(kLeftKnee, q[kLeftKnee]), kTolerance, 0.01);
    // Turned along the shortest way: what it gave up plus what is left is where it was.
    EXPECT_NEAR(rotation_between_deg(bent, q[kLeftKnee]) + kTolerance, was, 0.01);
    EXPECT_NEAR(q[kLeftKnee][0] * q[kLeftKnee][0] + q[kLeftKnee][1] * q[kLeftKnee][1]
                + q[kLeftKnee][2] * q[kLeftKnee][2] + q[kLeftKnee][3] * q[kLeftKnee][3], 1.0, 1e-12);

    double again[POSE_LIMITS_JOINTS][4];
    std::memcpy(again, q, sizeof q);
    EXPECT_EQ(pose_limits_apply(&s, kTolerance, again, nullptr), 0) << "a guarded pose is in range";
    EXPECT_EQ(std::memcmp(again, q, sizeof q), 0);
}

TEST(PoseLimits, TheAnswerDoesNotDependOnTheFrameBefore)
{
    double first[POSE_LIMITS_JOINTS][4], second[POSE_LIMITS_JOINTS][4];
    pose_in_range(first);
    turn(first[kRightElbow], 150.0, 0.0, 1.0, 0.0);   // an elbow twisted past any forearm
    turn(first[kHead], 100.0, 1.0, 0.0, 0.0);
    std::memcpy(second, first, sizeof first);

    pose_limits_state fresh, used;
    pose_limits_reset(&fresh);
    pose_limits_reset(&used);
    for (int j = 0; j < POSE_LIMITS_JOINTS; ++j)
        used.last_nearest[j] = pose_range_joints[j].count ? pose_range_joints[j].count - 1 : 0;
    used.last_nearest[kLeftKnee] = 1u << 30;   // out of the span: ignored
    EXPECT_EQ(pose_limits_apply(&fresh, kTolerance, first, nullptr), 2);
    EXPECT_EQ(pose_limits_apply(&used, kTolerance, second, nullptr), 2);
    EXPECT_EQ(std::memcmp(first, second, sizeof first), 0);
}

TEST(PoseLimits, AWiderToleranceLetsMoreThrough)
{
    double q[POSE_LIMITS_JOINTS][4];
    pose_in_range(q);
    turn(q[kHead], 60.0, 0.0, 0.0, 1.0);
    const double d = pose_limits_distance_deg(kHead, q[kHead]);
    ASSERT_GT(d, 5.0);
    pose_limits_state s;
    pose_limits_reset(&s);
    double wide[POSE_LIMITS_JOINTS][4];
    std::memcpy(wide, q, sizeof q);
    EXPECT_EQ(pose_limits_apply(&s, d + 1.0, wide, nullptr), 0);
    EXPECT_EQ(pose_limits_apply(&s, d - 1.0, q, nullptr), 1);
    EXPECT_NEAR(pose_limits_distance_deg(kHead, q[kHead]), d - 1.0, 0.01);
}

TEST(PoseLimits, NonFiniteAndZeroRotationsAreLeftAlone)
{
    double q[POSE_LIMITS_JOINTS][4];
    pose_in_range(q);
    q[kLeftKnee][0] = NAN;
    q[kHead][0] = q[kHead][1] = q[kHead][2] = q[kHead][3] = 0.0;
    pose_limits_state s;
    pose_limits_reset(&s);
    EXPECT_EQ(pose_limits_apply(&s, kTolerance, q, nullptr), 0);
    EXPECT_TRUE(std::isnan(q[kLeftKnee][0]));
    EXPECT_EQ(q[kHead][0], 0.0);
    EXPECT_EQ(pose_limits_distance_deg(0, q[1]), -1.0);
}
