/* Sensor sets: helpers over the segment table (segments.def). */
#ifndef MOCAP_SEGMENTS_H
#define MOCAP_SEGMENTS_H

#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The default sensor set in segment order; returns its size. */
uint32_t segments_default_set(int32_t segments[MOCAP_MAX_SENSORS], int32_t node_ids[MOCAP_MAX_SENSORS]);
/* Index of segment in segments[0..count), or -1. */
int segments_index_of(const int32_t *segments, uint32_t count, int32_t segment);
/* The segment's name, or fallback for a value outside the table. */
const char *segments_name_or(int32_t segment, const char *fallback);

#ifdef __cplusplus
}
#endif
#endif
