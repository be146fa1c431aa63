/* The sensor set of the sessions mocapctl opens: --sensors LIST, and which sensors a pose model
 * lets be missing. */
#ifndef MOCAPCTL_SENSOR_SET_H
#define MOCAPCTL_SENSOR_SET_H

#include <stddef.h>

#include "mocap_imu.h"

/* What --help says about --sensors. */
#define SENSOR_SET_HELP                                                                          \
    "  --sensors LIST       the sensor set: SEGMENT=NODE[,SEGMENT=NODE...], a '?' after an entry\n" \
    "                       marks it optional (e.g. pelvis=0,...,head=5,chest=6?); default\n"     \
    "                       pelvis=0,left_wrist=1,right_wrist=2,left_shin=3,right_shin=4,head=5\n"

/* Parses LIST into cfg's sensor_count, sensor_segments, node_ids and optional_mask (the rest of
 * cfg is left alone). 0, or -1 with the reason in `why` (the entry, the unknown segment, the
 * node used twice ...); cfg is then unchanged. */
int sensor_set_parse(const char *list, mocap_session_config *cfg, char *why, size_t why_cap);

/* --sensors of the command line into cfg (absent: cfg keeps its set). 0, or 2 after printing
 * the usage error. */
int sensor_set_from_args(int argc, char **argv, mocap_session_config *cfg);

/* Marks optional every sensor whose segment the model does not require (one it does not use
 * at all included), so calibration and the solver do not wait for it. */
void sensor_set_apply_model(mocap_session_config *cfg, const mocap_model_info *info);

/* "pelvis=0,left_wrist=1,...,chest=6?" of cfg's set into out. */
void sensor_set_describe(const mocap_session_config *cfg, char *out, size_t cap);

#endif
