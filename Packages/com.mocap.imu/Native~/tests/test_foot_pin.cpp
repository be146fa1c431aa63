// Foot pinning (src/pose/foot_pin.c): two-bone inverse kinematics of the legs and the hold of
// planted feet, on a hand-made skeleton with the SMPL joint order.
#include <gtest/gtest.h>

#include <cmath>

extern "C" {
#include "foot_pin.h"
#include "mocap_math.h"
#include "smpl_skeleton.h"
}

namespace {

const double kDt = 1.0 / 60.0;

skeleton legs()
{
    int32_t parents[MOCAP_JOINT_COUNT];
    float offsets[MOCAP_JOINT_COUNT][3];
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
        parents[j] = smpl_joint_parent(j);
        offsets[j][0] = 0.0f; offsets[j][1] = 0.1f; offsets[j][2] = 0.0f;   // the upper body
    }
    const float pelvis[3] = {0.0f, 0.93f, 0.0f};
    for (int k = 0; k < 3; ++k) offsets[0][k] = pelvis[k];
    for (int side = 0; side < 2; ++side) {
        const float x = side == 0 ? 0.08f : -0.08f;
        const int hip = side == 0 ? 1 : 2, knee = hip + 3, ankle = hip + 6, foot = hip + 9;
        offsets[hip][0] = x;    offsets[hip][1] = -0.08f;
        offsets[knee][1] = -0.4f;
        offsets[ankle][1] = -0.4f;
        offsets[foot][1] = -0.05f; offsets[foot][2] = 0.12f;
    }
    skeleton sk;
    EXPECT_EQ(skeleton_init(&sk, parents, offsets, MOCAP_JOINT_COUNT), MOCAP_OK);
    return sk;
}

// A walking-like pose: both hips and knees bent, the pelvis turned a little.
void bent_pose(double q[][4], double swing = 0.3)
{
    for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) quat_identity(q[j]);
    const double x[3] = {1, 0, 0}, y[3] = {0, 1, 0};
    quat_from_axis_angle(q[0], y, 0.2);
    quat_from_axis_angle(q[1], x, -swing);
    quat_from_axis_angle(q[4], x, 0.9);
    quat_from_axis_angle(q[2], x, swing);
    quat_from_axis_angle(q[5], x, 0.2);
    quat_from_axis_angle(q[7], x, -0.1);
}

void positions(const skeleton &sk, double q[][4], const double root[3], double p[][3],
               double g[][4] = nullptr)
{
    skeleton_fk(&sk, (const double (*)[4])q, root, g, p);
}

double distance(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return vec3_norm(d);
}

}  // namespace

TEST(FootPin, ReachPutsTheFootOnItsGoalAndMovesNothingElse)
{
    const skeleton sk = legs();
    double q[MOCAP_JOINT_COUNT][4], before[MOCAP_JOINT_COUNT][3], g0[MOCAP_JOINT_COUNT][4];
    bent_pose(q);
    const double root[3] = {0.3, 0.9, -0.2};
    positions(sk, q, root, before, g0);
    const double moves[4][3] = {{0.05, 0, 0}, {0, 0.04, 0.03}, {-0.06, -0.02, 0.05}, {0, 0, -0.08}};
    for (const auto &m : moves) {
        double qq[MOCAP_JOINT_COUNT][4];
        memcpy(qq, q, sizeof q);
        double goal[3] = {before[10][0] + m[0], before[10][1] + m[1], before[10][2] + m[2]};
        EXPECT_LT(foot_pin_reach(&sk, 1, 4, 7, 10, root, goal, qq), 1e-9);
        double after[MOCAP_JOINT_COUNT][3], g1[MOCAP_JOINT_COUNT][4];
        positions(sk, qq, root, after, g1);
        EXPECT_LT(distance(after[10], goal), 1e-9);
        EXPECT_LT(quat_angle_deg(g0[7], g1[7]), 1e-6) << "the ankle keeps its global rotation";
        EXPECT_LT(quat_angle_deg(g0[10], g1[10]), 1e-6);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j) {
            if (j == 4 || j == 7 || j == 10) continue;   // the moved leg's knee, ankle, foot
            EXPECT_LT(distance(after[j], before[j]), 1e-12) << "joint " << j;
        }
        for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isfinite(qq[1][k]) && std::isfinite(qq[4][k]));
    }
}

TEST(FootPin, AGoalOutOfReachStretchesTheLegTowardsIt)
{
    const skeleton sk = legs();
    double q[MOCAP_JOINT_COUNT][4], p[MOCAP_JOINT_COUNT][3];
    bent_pose(q);
    const double root[3] = {0, 0.9, 0};
    positions(sk, q, root, p);
    const double goal[3] = {p[10][0], p[10][1] - 0.5, p[10][2] + 0.2};   // below the floor of reach
    const double left = foot_pin_reach(&sk, 1, 4, 7, 10, root, goal, q);
    EXPECT_GT(left, 0.2);
    EXPECT_LT(left, 0.6);
    double after[MOCAP_JOINT_COUNT][3];
    positions(sk, q, root, after);
    EXPECT_NEAR(distance(after[7], after[1]), 0.8, 1e-4) << "the knee straight, not broken";
    EXPECT_NEAR(distance(after[4], after[1]), 0.4, 1e-7);   // float offsets
    EXPECT_NEAR(distance(after[7], after[4]), 0.4, 1e-7);
}

TEST(FootPin, AHyperextendedKneeBendsForwardToShortenTheLeg)
{
    // The predicted knee bent 6 deg backwards; holding the foot 3 cm higher needs a shorter leg.
    // Bending along the predicted knee's plane would fold it further backwards; the knee must
    // bend forward, the way knees bend, and still reach.
    const skeleton sk = legs();
    double q[MOCAP_JOINT_COUNT][4], p[MOCAP_JOINT_COUNT][3];
    bent_pose(q);
    const double x[3] = {1, 0, 0};
    quat_from_axis_angle(q[4], x, -0.1);
    const double root[3] = {0, 0.9, 0};
    positions(sk, q, root, p);
    const double down[3] = {0, -1, 0};
    double shin[3];
    quat_rotate(shin, q[4], down);
    ASSERT_GT(shin[2], 0.05) << "the shin points forward of the thigh: hyperextended";
    const double goal[3] = {p[10][0], p[10][1] + 0.03, p[10][2]};
    EXPECT_LT(foot_pin_reach(&sk, 1, 4, 7, 10, root, goal, q), 1e-9);
    quat_rotate(shin, q[4], down);
    EXPECT_LT(shin[2], -0.05) << "the knee now bends forward";
    // A straight knee bends forward too.
    bent_pose(q);
    quat_identity(q[4]);
    positions(sk, q, root, p);
    const double higher[3] = {p[10][0], p[10][1] + 0.03, p[10][2]};
    EXPECT_LT(foot_pin_reach(&sk, 1, 4, 7, 10, root, higher, q), 1e-9);
    quat_rotate(shin, q[4], down);
    EXPECT_LT(shin[2], -0.05);
}

TEST(FootPin, APlantedFootStaysPutWhileThePoseSlidesIt)
{
    // The pose's foot slides 2 mm a frame (3 cm in 15 frames, 12 cm/s) while the model says it
    // is planted: the shown foot stays where it landed.
    const skeleton sk = legs();
    foot_pin_params p = {kDt, 0.1, FOOT_PIN_RELEASE_S, 0.0};
    foot_pin_state s;
    foot_pin_reset(&s);
    const int left_down[2] = {1, 0};
    double landed[3] = {0, 0, 0};
    for (int i = 0; i < 15; ++i) {
        double q[MOCAP_JOINT_COUNT][4], shown[MOCAP_JOINT_COUNT][3];
        bent_pose(q);
        const double root[3] = {0.002 * i, 0.9, 0.0};
        foot_pin_apply(&s, &p, &sk, root, left_down, q);
        positions(sk, q, root, shown);
        if (i == 0) memcpy(landed, shown[10], sizeof landed);
        EXPECT_LT(distance(shown[10], landed), 1e-9) << i;
        double pose_only[MOCAP_JOINT_COUNT][3], q0[MOCAP_JOINT_COUNT][4];
        bent_pose(q0);
        positions(sk, q0, root, pose_only);
        EXPECT_LT(distance(shown[11], pose_only[11]), 1e-12) << "the foot in the air follows the pose";
    }
}

TEST(FootPin, TheHoldGivesWayAtMaxOffsetAndFadesAfterLiftOff)
{
    const skeleton sk = legs();
    foot_pin_params p = {kDt, 0.05, FOOT_PIN_RELEASE_S, 0.0};
    foot_pin_state s;
    foot_pin_reset(&s);
    const int down[2] = {1, 1}, up[2] = {0, 0};
    double last[3] = {0, 0, 0}, pose_foot[3] = {0, 0, 0};
    for (int i = 0; i < 60; ++i) {
        double q[MOCAP_JOINT_COUNT][4], shown[MOCAP_JOINT_COUNT][3], bare[MOCAP_JOINT_COUNT][3];
        bent_pose(q);
        const double root[3] = {0.01 * i, 0.9, 0.0};   // 60 cm/s of slide
        positions(sk, q, root, bare);
        foot_pin_apply(&s, &p, &sk, root, i < 30 ? down : up, q);
        positions(sk, q, root, shown);
        const double off = distance(shown[10], bare[10]);
        EXPECT_LE(off, 0.05 + 1e-9) << i;
        // The most a frame moves it: the pose's slide plus a frame's share of the fade.
        const double step = 0.01 + 0.05 * (1.0 - std::exp(-kDt / FOOT_PIN_RELEASE_S)) + 1e-9;
        if (i > 0) {
            EXPECT_LT(distance(shown[10], last), step) << "no jump, frame " << i;
        }
        if (i == 10) {
            EXPECT_NEAR(off, 0.05, 1e-9) << "held at the limit, dragged along";
        }
        if (i >= 30) {
            // After lift-off the offset fades by exp(-dt / release) a frame.
            const double expected = 0.05 * std::pow(std::exp(-kDt / FOOT_PIN_RELEASE_S), i - 29);
            EXPECT_NEAR(off, expected, 1e-6) << i;
        }
        memcpy(last, shown[10], sizeof last);
        memcpy(pose_foot, bare[10], sizeof pose_foot);
    }
    EXPECT_LT(distance(last, pose_foot), 0.05 * 0.01);
}

TEST(FootPin, OffOrWithoutLegsLeavesThePoseAlone)
{
    skeleton sk = legs();
    foot_pin_params p = {kDt, 0.0, FOOT_PIN_RELEASE_S, 0.0};
    foot_pin_state s;
    foot_pin_reset(&s);
    double q[MOCAP_JOINT_COUNT][4], q0[MOCAP_JOINT_COUNT][4];
    const int down[2] = {1, 1};
    for (int i = 0; i < 5; ++i) {
        bent_pose(q);
        const double root[3] = {0.01 * i, 0.9, 0};
        EXPECT_EQ(foot_pin_apply(&s, &p, &sk, root, down, q), 0);
    }
    bent_pose(q0);
    EXPECT_EQ(memcmp(q, q0, sizeof q), 0);
    // A skeleton whose leg chain is not SMPL's: pinning cannot know its legs.
    p.max_offset = 0.1;
    sk.parents[10] = 4;
    foot_pin_reset(&s);
    for (int i = 0; i < 5; ++i) {
        bent_pose(q);
        const double root[3] = {0.01 * i, 0.9, 0};
        EXPECT_EQ(foot_pin_apply(&s, &p, &sk, root, down, q), 0);
    }
}

TEST(FootPin, ANonFinitePoseIsNotHeldOnto)
{
    const skeleton sk = legs();
    foot_pin_params p = {kDt, 0.05, FOOT_PIN_RELEASE_S, 0.06};
    foot_pin_state s;
    foot_pin_reset(&s);
    const int down[2] = {1, 1};
    double q[MOCAP_JOINT_COUNT][4];
    for (int i = 0; i < 10; ++i) {
        bent_pose(q);
        const double root[3] = {0.01 * i, 0.9, 0};
        foot_pin_apply(&s, &p, &sk, root, down, q);
    }
    bent_pose(q);
    const double broken[3] = {NAN, 0.9, 0};
    foot_pin_apply(&s, &p, &sk, broken, down, q);
    for (int i = 0; i < 5; ++i) {
        bent_pose(q);
        const double root[3] = {0.2 + 0.01 * i, 0.9, 0};
        foot_pin_apply(&s, &p, &sk, root, down, q);
        double shown[MOCAP_JOINT_COUNT][3];
        positions(sk, q, root, shown);
        for (int j = 0; j < MOCAP_JOINT_COUNT; ++j)
            for (int k = 0; k < 3; ++k) ASSERT_TRUE(std::isfinite(shown[j][k])) << i << " joint " << j;
    }
}
