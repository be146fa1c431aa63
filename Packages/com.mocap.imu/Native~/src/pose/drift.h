/* Root motion: the pose model predicts the pelvis velocity, not its position. The engine
 * integrates the velocity at the model's frame rate and corrects the drift with the predicted
 * foot contacts. Pure functions on a small state, no allocation, unit-tested in
 * tests/test_drift.cpp.
 *
 * The rule, applied once per frame after integrating root += velocity * dt:
 *  1. Less sliding: a foot whose contact probability is >= threshold in this frame AND in the
 *     previous frame is planted; the root moves horizontally by foot_lock times the (x, z)
 *     distance the foot slid since the previous frame (the mean of the two feet's when both are
 *     planted). foot_lock 1 holds a planted foot exactly still; the engine takes back a quarter
 *     (DRIFT_FOOT_LOCK) of each frame's slip, because the feet come from the predicted leg pose,
 *     whose own errors a full lock would pass on to the root (on held-out people a full lock made
 *     the 10 s drift worse than the model's velocity alone).
 *  2. On the floor: if any foot is in contact this frame, the root moves vertically so that the
 *     lowest foot in contact has its sole on the floor (sole = foot joint height minus the foot
 *     joint's rest height above the sole).
 *  3. Never below the floor: if, after that, any foot's sole is below the floor, the root is lifted
 *     until the lowest sole is on it (also without contact).
 * With correction disabled the root is the pure integral of the velocity. */
#ifndef MOCAP_DRIFT_H
#define MOCAP_DRIFT_H

#ifdef __cplusplus
extern "C" {
#endif

/* The engine's foot_lock: chosen on the training subjects' byte-level replays (a quarter gave
 * the least 10 s drift of 0, 0.1, 0.25, 0.5 and 1), reported on the others by
 * `python3 -m training engine-eval`. */
#define DRIFT_FOOT_LOCK 0.25

typedef struct drift_params {
    double dt;                /* seconds per model frame (1 / frame rate) */
    double contact_threshold; /* probability that counts as planted */
    double floor_height;      /* metres, model frame (y) */
    double foot_height[2];    /* rest height of the left/right foot joint above its sole */
    double foot_lock;         /* 0..1: share of a planted foot's horizontal slip taken back */
    int enabled;              /* 0: pure integration */
} drift_params;

typedef struct drift_state {
    int initialized;
    double root[3];           /* root (pelvis) position after the last step */
    double foot[2][3];        /* world positions of the feet after the last step */
    int contact[2];           /* contact >= threshold in the last step */
} drift_state;

/* Start at root position start (e.g. the rest pelvis position), no previous contact. */
void drift_reset(drift_state *s, const double start[3]);

/* One frame. velocity: root velocity (m/s); contact: left/right probabilities; foot_rel: the
 * feet positions relative to the root from forward kinematics of this frame's pose.
 * root_out receives the corrected root; returns 1 when a correction moved the root. */
int drift_step(drift_state *s, const drift_params *p, const double velocity[3],
               const double contact[2], const double foot_rel[2][3], double root_out[3]);

#ifdef __cplusplus
}
#endif
#endif
