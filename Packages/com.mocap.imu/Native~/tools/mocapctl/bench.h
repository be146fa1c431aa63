/* Micro-benchmarks behind `mocapctl bench`. */
#ifndef MOCAPCTL_BENCH_H
#define MOCAPCTL_BENCH_H

#include <stdint.h>

#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Decode a generated 6-node 0x62 stream (a few MB, fed in 4 KB chunks) repeatedly for about
 * `seconds` on the calling thread, verify that every frame came out, print the throughput to
 * stdout and store it in *mb_per_s (10^6 bytes per second; may be NULL). Returns 0 (MOCAP_OK),
 * or a mocap_status after printing the cause to stderr. */
int mocapctl_bench_decode(double seconds, double *mb_per_s);

/* The engine with the pose model (figures printed to stdout, nothing timed-asserted):
 *   pipeline  end-to-end frames/s of one character on a fast replay, peak RSS after it, and the
 *             latency benchmark below
 *   latency   byte arrival -> pose available (p50/p99) on a live serial session: a pseudo-terminal
 *             fed with the capture at its recorded 100 Hz pace
 *   scaling   1, 2, 4 ... 32 characters replayed through one solver
 *   tip       the TIP-shaped network (python3 -m training tip-model) re-run over a 40-frame window
 *             per frame vs our model at T = 1, same ONNX Runtime; the ratio per character
 *   all       all of them, in that order (one character first, so the RSS is one character's)
 * The capture is generated into a temporary directory (synth, mixed motion). Returns 0, 1 on a
 * failure (printed), 2 for an unknown benchmark. */
typedef struct mocapctl_bench_options {
    const char *model_path;     /* the pose model (required) */
    const char *tip_model_path; /* NULL: $MOCAP_TIP_MODEL or made with the training CLI */
    const char *repo_root;      /* for `python3 -m training tip-model`; NULL when unknown */
    double seconds;             /* motion seconds of the generated capture (30) */
    double latency_seconds;     /* live session length for the latency (10) */
    double tip_seconds;         /* seconds per model in the TIP comparison (3) */
    int threads;                /* ONNX Runtime intra-op threads in the TIP comparison (1) */
    int max_characters;         /* scaling stops above this (32) */
    /* The sensors of the generated capture and of the sessions (sensor_count 0: the default
     * set); the model's optional sensors become optional. */
    uint32_t sensor_count;
    int32_t sensor_segments[MOCAP_MAX_SENSORS];
    int32_t node_ids[MOCAP_MAX_SENSORS];
    uint32_t optional_mask;
} mocapctl_bench_options;

int mocapctl_bench_model(const char *which, const mocapctl_bench_options *options);

#ifdef __cplusplus
}
#endif
#endif
