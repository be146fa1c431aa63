// The spine turned towards a chest sensor (src/pose/chest_follow.c): the chest bone moves the
// asked share of the way to the sensor, the turn is spread over the spine, and the bones the
// rule promises to leave alone keep their local or global rotations.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

extern "C" {
#include "chest_follow.h"
#include "mocap_math.h"
#include "smpl_skeleton.h"
}

namespace {

const int kJoints = MOCAP_JOINT_COUNT;
const int kNeck = 12, kLeftCollar = 13, kRightCollar = 14, kHead = 15, kLeftArm = 16, kRightArm = 17;

void random_pose(mocap_rng *rng, double q[kJoints][4])
{
    mocap_rng_rotation(rng, q[0]);
    for (int j = 1; j < kJoints; ++j) {
        // Joints bent by up to ~50 deg, as bodies bend; the root anywhere.
        double axis[3] = {mocap_rng_gaussian(rng), mocap_rng_gaussian(rng), mocap_rng_gaussian(rng)};
        const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        for (double &a : axis) a /= n;
        quat_from_axis_angle(q[j], axis, 0.9 * mocap_rng_uniform(rng));
    }
}

void globals(const double q[kJoints][4], double g[kJoints][4])
{
    quat_copy(g[0], q[0]);
    for (int j = 1; j < kJoints; ++j) quat_multiply(g[j], g[smpl_joint_parent(j)], q[j]);
}

double angle_deg(const double a[4], const double b[4]) { return quat_angle_deg(a, b); }

// The chest sensor: the model's chest bone turned by angle_deg about an arbitrary axis.
void chest_sensor(mocap_rng *rng, const double chest_bone[4], double angle_deg_, double out[4])
{
    double axis[3] = {mocap_rng_gaussian(rng), mocap_rng_gaussian(rng), mocap_rng_gaussian(rng)};
    const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (double &a : axis) a /= n;
    double turn[4];
    quat_from_axis_angle(turn, axis, angle_deg_ * MOCAP_DEG2RAD);
    quat_multiply(out, turn, chest_bone);
}

}  // namespace

TEST(ChestFollow, MovesTheChestTheSharedWayAndSpreadsItOverTheSpine)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 7);
    for (int trial = 0; trial < 50; ++trial) {
        double q[kJoints][4], before[kJoints][4], after[kJoints][4], chest[4];
        random_pose(&rng, q);
        globals(q, before);
        const double off = 2.0 + 40.0 * mocap_rng_uniform(&rng);
        chest_sensor(&rng, before[CHEST_FOLLOW_SPINE3], off, chest);
        const double share = trial % 2 ? 0.5 : 0.25 + 0.75 * mocap_rng_uniform(&rng);
        ASSERT_EQ(chest_follow_apply(q, chest, share), 0);
        globals(q, after);
        EXPECT_NEAR(angle_deg(before[CHEST_FOLLOW_SPINE3], after[CHEST_FOLLOW_SPINE3]), share * off, 1e-6);
        EXPECT_NEAR(angle_deg(after[CHEST_FOLLOW_SPINE3], chest), (1.0 - share) * off, 1e-6);
        // The lower spine joints take two thirds and all of the turn, in the world frame, and
        // spine3 keeps its bend from spine2.
        EXPECT_NEAR(angle_deg(before[CHEST_FOLLOW_SPINE1], after[CHEST_FOLLOW_SPINE1]), 2.0 * share * off / 3.0, 1e-6);
        EXPECT_NEAR(angle_deg(before[CHEST_FOLLOW_SPINE2], after[CHEST_FOLLOW_SPINE2]), share * off, 1e-6);
        {
            double inv[4], bend_before[4], bend_after[4];
            quat_conjugate(inv, before[CHEST_FOLLOW_SPINE2]);
            quat_multiply(bend_before, inv, before[CHEST_FOLLOW_SPINE3]);
            quat_conjugate(inv, after[CHEST_FOLLOW_SPINE2]);
            quat_multiply(bend_after, inv, after[CHEST_FOLLOW_SPINE3]);
            EXPECT_LT(angle_deg(bend_before, bend_after), 1e-6);
        }
        for (int j : {kNeck, kLeftCollar, kRightCollar})
            EXPECT_NEAR(angle_deg(before[j], after[j]), share * off, 1e-6) << "joint " << j;
        for (int j : {kHead, kLeftArm, kRightArm})
            EXPECT_LT(angle_deg(before[j], after[j]), 1e-6) << "joint " << j << " keeps its global rotation";
        // Pelvis, legs and everything below the upper arms keep their local rotations.
        for (int j : {0, 1, 2, 4, 5, 7, 8, 10, 11, 18, 19, 20, 21, 22, 23}) {
            double local_before[4], local_after[4], inv[4];
            if (j == 0) {
                quat_copy(local_before, before[0]);
                quat_copy(local_after, after[0]);
            } else {
                quat_conjugate(inv, before[smpl_joint_parent(j)]);
                quat_multiply(local_before, inv, before[j]);
                quat_conjugate(inv, after[smpl_joint_parent(j)]);
                quat_multiply(local_after, inv, after[j]);
            }
            EXPECT_LT(angle_deg(local_before, local_after), 1e-6) << "joint " << j;
        }
        for (int j = 0; j < kJoints; ++j) EXPECT_NEAR(quat_norm(q[j]), 1.0, 1e-12);
    }
}

TEST(ChestFollow, ShareZeroLeavesThePoseAndShareOneReachesTheSensor)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 11);
    double q[kJoints][4], copy[kJoints][4], g[kJoints][4], chest[4];
    random_pose(&rng, q);
    globals(q, g);
    chest_sensor(&rng, g[CHEST_FOLLOW_SPINE3], 30.0, chest);
    std::memcpy(copy, q, sizeof q);
    ASSERT_EQ(chest_follow_apply(q, chest, 0.0), 0);
    EXPECT_EQ(std::memcmp(copy, q, sizeof q), 0);
    ASSERT_EQ(chest_follow_apply(q, chest, 1.0), 0);
    globals(q, g);
    EXPECT_LT(angle_deg(g[CHEST_FOLLOW_SPINE3], chest), 1e-6);
}

TEST(ChestFollow, RefusesABadShareOrChestAndLeavesThePose)
{
    mocap_rng rng;
    mocap_rng_seed(&rng, 3);
    double q[kJoints][4], copy[kJoints][4];
    random_pose(&rng, q);
    std::memcpy(copy, q, sizeof q);
    const double good[4] = {1.0, 0.0, 0.0, 0.0}, zero[4] = {0.0, 0.0, 0.0, 0.0};
    const double nan_chest[4] = {NAN, 0.0, 0.0, 1.0};
    EXPECT_EQ(chest_follow_apply(q, good, -0.1), -1);
    EXPECT_EQ(chest_follow_apply(q, good, 1.5), -1);
    EXPECT_EQ(chest_follow_apply(q, good, NAN), -1);
    EXPECT_EQ(chest_follow_apply(q, zero, 0.5), -1);
    EXPECT_EQ(chest_follow_apply(q, nan_chest, 0.5), -1);
    EXPECT_EQ(std::memcmp(copy, q, sizeof q), 0);
}
