/* A replay session of a capture with its calibration arranged, shared by replay and stream. */
#ifndef MOCAPCTL_REPLAY_SESSION_H
#define MOCAPCTL_REPLAY_SESSION_H

#include "mocap_imu.h"

/* Opens a replay of `capture` (cfg says how) and arranges its calibration: a saved file
 * (`calibration_path`), or the heading and T-pose windows of the capture's prelude (`prelude`
 * "H,S,T" seconds; NULL: synth's layout, heading 0-3 s, strap 3-5 s, T-pose 5-8 s; the middle of
 * each window is used), both queued before the start because a fast replay would outrun a caller
 * reacting to results. The session is not started. 0, or 1 after printing why (*out may then
 * hold a session to close). */
int replay_session_open(const char *capture, mocap_session_config *cfg, const char *prelude,
                        const char *calibration_path, mocap_session **out);

#endif
