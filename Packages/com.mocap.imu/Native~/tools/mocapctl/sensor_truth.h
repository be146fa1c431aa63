/* The sensor truth CSV synth writes (--truth): per row the session time, the prelude/motion
 * phase, then per sensor the bone orientation (qw qx qy qz) and acceleration (ax ay az), the
 * header naming each sensor's segment (pelvis_qw ...). */
#ifndef MOCAPCTL_SENSOR_TRUTH_H
#define MOCAPCTL_SENSOR_TRUTH_H

#include <stddef.h>

#include "mocap_imu.h"

/* One row, indexed by segment (mocap_segment); only the file's segments are filled. */
typedef struct sensor_truth_row {
    double t;
    int phase; /* 3: the motion, after the calibration prelude */
    double q[MOCAP_MAX_SENSORS][4];
    double a[MOCAP_MAX_SENSORS][3];
} sensor_truth_row;

typedef struct sensor_truth {
    sensor_truth_row *rows;
    size_t count;
    size_t cursor;
    int segment_count;                   /* column groups of the file */
    int32_t segments[MOCAP_MAX_SENSORS]; /* the segment of each */
    uint32_t segment_mask;               /* bit s: the file has segment s */
} sensor_truth;

/* Reads `path` (damaged rows skipped). A file without a header row holds the engine's default
 * set. 0, or -1 after printing why (nothing to free then); sensor_truth_free releases a loaded
 * table. */
int sensor_truth_load(const char *path, sensor_truth *table);
void sensor_truth_free(sensor_truth *table);

/* The truth at time t, interpolated between rows: 0, or -1 outside the table's time range.
 * Queries must come in time order (the table keeps its place). */
int sensor_truth_at(sensor_truth *table, double t, sensor_truth_row *out);

#endif
