/* Foot pinning: a foot the model says is planted stays where it landed in the pose the engine
 * outputs. The root is left to drift correction (drift.h); only the leg moves. A planted foot is
 * held at its landing point by two-bone inverse kinematics of hip and knee, the ankle keeping its
 * predicted global orientation (so the sole keeps its predicted roll). The hold gives way where
 * the pose and the pin part: the foot is held at most max_offset from where the pose puts it, and
 * after lift-off the remaining offset fades with time constant release_s, so nothing jumps.
 * Pure functions on a small state, no allocation, unit-tested in tests/test_foot_pin.cpp. */
#ifndef MOCAP_FOOT_PIN_H
#define MOCAP_FOOT_PIN_H

#include "skeleton_fk.h"

#ifdef __cplusplus
extern "C" {
#endif

/* SMPL leg chains (the contract's joint order): hip, knee, ankle, foot. */
#define FOOT_PIN_LEFT_HIP 1
#define FOOT_PIN_LEFT_KNEE 4
#define FOOT_PIN_LEFT_ANKLE 7
#define FOOT_PIN_RIGHT_HIP 2
#define FOOT_PIN_RIGHT_KNEE 5
#define FOOT_PIN_RIGHT_ANKLE 8

/* The fade after lift-off, a time constant: a tenth of a second (a step's swing lasts about
 * four), so the leg is back on the prediction before the foot lands again. */
#define FOOT_PIN_RELEASE_S 0.1
/* The farthest a held foot is from the predicted one: the further the hold, the more of the
 * leg's predicted pose it bends away (training subjects' replays, mean joint angle against the
 * unpinned output: held still, +0.31 deg at 0.05 m, +0.48 at 0.1 m, +0.67 at 0.2 m; sliding at
 * 0.03 m/s, +0.07 deg at 0.03 m and +0.10 at 0.05 m). */
#define FOOT_PIN_MAX_OFFSET_M 0.05

typedef struct foot_pin_params {
    double dt;           /* seconds per pose */
    double max_offset;   /* metres a held foot may be from where the pose puts it; 0: off */
    double release_s;    /* time constant of the fade after lift-off */
    double creep_speed;  /* m/s a held point follows the pose at (0: held still) */
} foot_pin_params;

typedef struct foot_pin_state {
    int planted[2];
    double target[2][3];   /* world position a planted foot is held at */
    double offset[2][3];   /* shown minus predicted foot position, world axes */
} foot_pin_state;

void foot_pin_reset(foot_pin_state *s);

/* Moves the foot joints (SKELETON_LEFT_FOOT, SKELETON_RIGHT_FOOT) of the pose with local
 * rotations q (joint 0 global) and root position root to where they are held: planted[f] says
 * whether foot f is in contact this frame. Rewrites q's hip, knee and ankle rotations of a leg
 * it moves. Returns how many legs it moved. A skeleton without the SMPL leg chain is left alone. */
int foot_pin_apply(foot_pin_state *s, const foot_pin_params *p, const skeleton *sk,
                   const double root[3], const int planted[2], double (*q)[4]);

/* Two-bone inverse kinematics of one leg: rewrites q[hip], q[knee], q[ankle] so that joint foot
 * reaches goal (world, with joint 0 at root) as nearly as the bone lengths allow, the ankle
 * keeping its global rotation and the knee bending forward (about its own x axis, as SMPL's
 * knees flex). Returns the distance left to the goal (m). */
double foot_pin_reach(const skeleton *sk, int hip, int knee, int ankle, int foot,
                      const double root[3], const double goal[3], double (*q)[4]);

#ifdef __cplusplus
}
#endif
#endif
