/* A session on a live serial port, shared by live, record and stream: opening it from the
 * command line, the status line, and the guided calibration steps. */
#ifndef MOCAPCTL_LIVE_SESSION_H
#define MOCAPCTL_LIVE_SESSION_H

#include "mocap_imu.h"

/* Opens and starts a session on --port (--baud) with the sensors of --sensors, recording to
 * `record_path` when not NULL, at `rate_hz` (0: the default rate); with a model (may be NULL)
 * the sensors it does not require are optional. Without --port, `command`'s usage. 0, or
 * nonzero after printing why (*out is then NULL or a session to close). */
int live_session_open(const char *command, int argc, char **argv, const char *record_path,
                      float rate_hz, const mocap_model_info *model, mocap_session **out);

/* Names the sensors in the order of the status line, then refreshes a one-line status
 * (connection, frames, CRC failures, each sensor's state) ten times a second until Ctrl-C or
 * `limit_s` seconds. */
void live_session_show_status(mocap_session *session, double limit_s);

/* live_session_guided_step's result when the receiver delivered nothing. */
#define GUIDED_STEP_NO_FRAMES 2

/* One calibration step with a countdown after printing `instruction`. 0 accepted, 1 refused or
 * interrupted, GUIDED_STEP_NO_FRAMES when no frame came within a few seconds (the window only
 * opens with the first frame, so without this a wrong port or baud rate would wait forever). */
int live_session_guided_step(mocap_session *session, int step, const char *instruction,
                             float seconds);

#endif
