// Root integration and contact-based drift correction (src/pose/drift.c) on synthetic sequences.
#include <gtest/gtest.h>

#include <cmath>

extern "C" {
#include "drift.h"
}

namespace {

const double kDt = 1.0 / 60.0;

drift_params params(int enabled = 1)
{
    drift_params p;
    p.dt = kDt;
    p.contact_threshold = 0.5;
    p.floor_height = 0.0;
    p.foot_height[0] = 0.05;   // the foot joint sits 5 cm above its sole at rest
    p.foot_height[1] = 0.05;
    p.foot_lock = 1.0;         // a full lock unless a test says otherwise
    p.enabled = enabled;
    return p;
}

// Feet hanging below a pelvis at 0.93 m: soles exactly on the floor when the root is at 0.93.
void standing_feet(double feet[2][3], double swing_x = 0.0)
{
    feet[0][0] = 0.1 + swing_x; feet[0][1] = -0.88; feet[0][2] = 0.0;
    feet[1][0] = -0.1 - swing_x; feet[1][1] = -0.88; feet[1][2] = 0.0;
}

}  // namespace

TEST(Drift, NoContactIsPureIntegration)
{
    drift_params p = params();
    drift_state s;
    const double start[3] = {0.0, 0.93, 0.0};
    drift_reset(&s, start);
    const double v[3] = {1.0, 0.0, -0.5};
    const double contact[2] = {0.1, 0.49};
    double feet[2][3];
    standing_feet(feet);
    feet[0][1] = feet[1][1] = -0.7;  // feet in the air: no floor correction either
    double root[3];
    for (int i = 1; i <= 120; ++i) {
        EXPECT_EQ(drift_step(&s, &p, v, contact, feet, root), 0) << i;
        EXPECT_NEAR(root[0], 1.0 * kDt * i, 1e-9);
        EXPECT_NEAR(root[1], 0.93, 1e-12);
        EXPECT_NEAR(root[2], -0.5 * kDt * i, 1e-9);
    }
}

TEST(Drift, PlantedFootDoesNotSlideWhateverTheVelocitySays)
{
    drift_params p = params();
    drift_state s;
    const double start[3] = {0.0, 0.93, 0.0};
    drift_reset(&s, start);
    const double v[3] = {0.8, 0.0, 0.3};  // the network says: sliding
    const double contact[2] = {0.9, 0.9};
    double feet[2][3];
    standing_feet(feet);
    double root[3];
    drift_step(&s, &p, v, contact, feet, root);  // first contact frame: nothing to hold yet
    const double foot0[2][2] = {{root[0] + feet[0][0], root[2] + feet[0][2]},
                                {root[0] + feet[1][0], root[2] + feet[1][2]}};
    for (int i = 0; i < 90; ++i) {
        EXPECT_EQ(drift_step(&s, &p, v, contact, feet, root), 1);
        for (int f = 0; f < 2; ++f) {
            EXPECT_NEAR(root[0] + feet[f][0], foot0[f][0], 1e-12) << i;
            EXPECT_NEAR(root[2] + feet[f][2], foot0[f][1], 1e-12) << i;
        }
    }
    // Uncorrected, the root would have travelled 0.8 * 1.5 s = 1.2 m.
    EXPECT_NEAR(root[0], foot0[0][0] - feet[0][0], 1e-12);
}

TEST(Drift, StanceLegCarriesTheBodyForward)
{
    // Left foot planted while the leg swings back relative to the pelvis (a walk's stance):
    // the root advances by exactly what keeps the planted foot still, whatever the velocity.
    drift_params p = params();
    drift_state s;
    const double start[3] = {0.0, 0.93, 0.0};
    drift_reset(&s, start);
    const double v[3] = {0.0, 0.0, 0.0};
    const double contact[2] = {0.95, 0.05};  // right foot in the air
    double feet[2][3], root[3];
    standing_feet(feet);
    drift_step(&s, &p, v, contact, feet, root);
    double planted_z = root[2] + feet[0][2];
    for (int i = 1; i <= 30; ++i) {
        feet[0][2] = -0.01 * i;        // stance foot moves backwards under the body
        feet[1][2] = +0.02 * i;        // swing foot moves forwards: must not matter
        feet[1][1] = -0.8;
        drift_step(&s, &p, v, contact, feet, root);
        EXPECT_NEAR(root[2] + feet[0][2], planted_z, 1e-12);
        EXPECT_NEAR(root[2], 0.01 * i, 1e-12);
    }
}

TEST(Drift, ContactStartingThisFrameIsNotHeldYet)
{
    drift_params p = params();
    drift_state s;
    const double start[3] = {0.0, 0.93, 0.0};
    drift_reset(&s, start);
    const double v[3] = {1.0, 0.0, 0.0};
    double feet[2][3], root[3];
    standing_feet(feet);
    const double off[2] = {0.0, 0.0}, on[2] = {1.0, 1.0};
    drift_step(&s, &p, v, off, feet, root);
    drift_step(&s, &p, v, on, feet, root);  // touchdown: integration still applies
    EXPECT_NEAR(root[0], 2 * kDt, 1e-12);
    drift_step(&s, &p, v, on, feet, root);  // planted from now on
    EXPECT_NEAR(root[0], 2 * kDt, 1e-12);
}

TEST(Drift, PlantedFootIsPulledToTheFloorAndNothingPenetratesIt)
{
    drift_params p = params();
    p.floor_height = 0.02;
    drift_state s;
    const double start[3] = {0.0, 1.2, 0.0};  // integrated height drifted 27 cm up
    drift_reset(&s, start);
    const double still[3] = {0, 0, 0};
    double feet[2][3], root[3];
    standing_feet(feet);
    feet[1][1] = -0.80;  // right foot 8 cm higher than the left
    const double left_contact[2] = {0.9, 0.1};
    EXPECT_EQ(drift_step(&s, &p, still, left_contact, feet, root), 1);
    // Left sole on the floor: root + (-0.88) - 0.05 = 0.02.
    EXPECT_NEAR(root[1], 0.95, 1e-12);

    // Right foot in contact but higher than the left (not in contact): the contact foot is put
    // on the floor, then the left foot would be under it, so the body is lifted.
    const double right_contact[2] = {0.1, 0.9};
    drift_step(&s, &p, still, right_contact, feet, root);
    EXPECT_NEAR(root[1] + feet[0][1] - 0.05, 0.02, 1e-12);  // lowest sole on the floor
    EXPECT_GE(root[1] + feet[1][1] - 0.05, 0.02 - 1e-12);

    // No contact, sinking velocity: the root never takes a sole below the floor.
    const double sink[3] = {0.0, -3.0, 0.0};
    const double none[2] = {0.0, 0.0};
    for (int i = 0; i < 30; ++i) {
        drift_step(&s, &p, sink, none, feet, root);
        double lowest = std::fmin(root[1] + feet[0][1], root[1] + feet[1][1]) - 0.05;
        EXPECT_GE(lowest, 0.02 - 1e-12) << i;
    }
    // No contact and above the floor: left alone (a jump).
    const double up[3] = {0.0, 1.0, 0.0};
    double before = root[1];
    EXPECT_EQ(drift_step(&s, &p, up, none, feet, root), 0);
    EXPECT_NEAR(root[1], before + kDt, 1e-12);
}

TEST(Drift, DisabledIsPureIntegrationEvenWithContact)
{
    drift_params p = params(0);
    drift_state s;
    const double start[3] = {0.0, 0.5, 0.0};  // feet would be far below the floor
    drift_reset(&s, start);
    const double v[3] = {0.3, -0.1, 0.2};
    const double contact[2] = {1.0, 1.0};
    double feet[2][3], root[3];
    standing_feet(feet);
    for (int i = 1; i <= 60; ++i) {
        EXPECT_EQ(drift_step(&s, &p, v, contact, feet, root), 0);
        EXPECT_NEAR(root[0], 0.3 * kDt * i, 1e-9);
        EXPECT_NEAR(root[1], 0.5 - 0.1 * kDt * i, 1e-9);
        EXPECT_NEAR(root[2], 0.2 * kDt * i, 1e-9);
    }
}

TEST(Drift, APartialLockTakesBackItsShareOfEachFramesSlip)
{
    // The engine's lock: a planted foot the velocity would slide by v * dt per frame slides by
    // (1 - foot_lock) of that; vertical motion and feet in the air are untouched by it.
    drift_params p = params();
    p.foot_lock = DRIFT_FOOT_LOCK;
    drift_state s;
    const double start[3] = {0.0, 0.93, 0.0};
    drift_reset(&s, start);
    const double v[3] = {0.6, 0.0, -0.3};
    const double contact[2] = {0.9, 0.9};
    double feet[2][3], root[3];
    standing_feet(feet);
    drift_step(&s, &p, v, contact, feet, root);   // touchdown: pure integration
    double x0 = root[0], z0 = root[2];
    for (int i = 1; i <= 60; ++i) {
        EXPECT_EQ(drift_step(&s, &p, v, contact, feet, root), 1);
        EXPECT_NEAR(root[0] - x0, (1.0 - DRIFT_FOOT_LOCK) * 0.6 * kDt * i, 1e-12) << i;
        EXPECT_NEAR(root[2] - z0, (1.0 - DRIFT_FOOT_LOCK) * -0.3 * kDt * i, 1e-12) << i;
        EXPECT_NEAR(root[1], 0.93, 1e-12);   // soles stay on the floor
    }
    // Lock 0: the velocity alone, even with both feet planted (the floor still applies).
    p.foot_lock = 0.0;
    drift_reset(&s, start);
    drift_step(&s, &p, v, contact, feet, root);
    for (int i = 2; i <= 30; ++i) {
        drift_step(&s, &p, v, contact, feet, root);
        EXPECT_NEAR(root[0], 0.6 * kDt * i, 1e-12) << i;
    }
}
