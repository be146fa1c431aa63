/* What went wrong in a mocapctl command, said on stderr in one place so that every command says
 * it the same way: engine errors, paths the engine cannot take, and the losses the engine only
 * counts (inference failures, dropped data, damaged captures). */
#ifndef MOCAPCTL_REPORT_H
#define MOCAPCTL_REPORT_H

#include <stdint.h>

#include "mocap_imu.h"

/* "mocapctl: WHAT: the engine's last error (STATUS)"; returns 1, the failed command's status. */
int report_failure(mocap_status status, const char *what);

/* The engine's path fields hold MOCAP_PATH_MAX bytes: a longer path would be cut short and open
 * (or, for a recording, overwrite) another file. 0 when it fits, else 1 after saying so. */
int report_path_too_long(const char *path, const char *what);

/* Inference fails on the solver's thread, where no call returns it: said at the end of a pose
 * command. 1 when some frame's inference failed (its pose repeats the previous one), else 0.
 * `solver` may be NULL. */
int report_inference_failures(mocap_solver *solver);

/* A realtime replay paced faster than processing, or a live session whose consumer stalled,
 * loses data on the way: the engine counts it (input bytes, frames, poses) but says nothing.
 * Said after the run, with `remedy`; `solver` may be NULL. */
void report_dropped(mocap_session *session, mocap_solver *solver, int32_t character,
                    const char *what, const char *remedy);

/* The replay skips damaged chunks and a cut-off end, as it must for a crash-damaged file; said
 * after the run, so that output made from part of a capture is not taken for the whole. */
void report_capture_damage(mocap_session *session, const char *capture);

/* A replay whose file stopped reading ends early, with the cause in the stats: 1 after saying
 * so (the output covers only part of the capture), 0 when the replay read to the end. */
int report_replay_ended_early(mocap_session *session);

#endif
