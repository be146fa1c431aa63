/* The sensor truth CSV synth writes (--truth): per row the session time, the prelude/motion
 * phase, then per segment the bone orientation (qw qx qy qz) and acceleration (ax ay az). */
#ifndef MOCAPCTL_SENSOR_TRUTH_H
#define MOCAPCTL_SENSOR_TRUTH_H

#include <stddef.h>

#include "mocap_imu.h"

typedef struct sensor_truth_row {
    double t;
    int phase; /* 3: the motion, after the calibration prelude */
    double q[MOCAP_SENSOR_COUNT][4];
    double a[MOCAP_SENSOR_COUNT][3];
} sensor_truth_row;

typedef struct sensor_truth {
    sensor_truth_row *rows;
    size_t count;
    size_t cursor;
} sensor_truth;

/* Reads `path` (damaged rows skipped). 0, or -1 after printing why (nothing to free then);
 * sensor_truth_free releases a loaded table. */
int sensor_truth_load(const char *path, sensor_truth *table);
void sensor_truth_free(sensor_truth *table);

/* The truth at time t, interpolated between rows: 0, or -1 outside the table's time range.
 * Queries must come in time order (the table keeps its place). */
int sensor_truth_at(sensor_truth *table, double t, sensor_truth_row *out);

#endif
