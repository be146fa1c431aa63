/* Frame assembly: turns per-sensor samples (each sensor on its own clock and rate) into
 * synchronised frames at a fixed output rate, interpolating each sensor to the frame time
 * (slerp for orientation, linear for vectors). A sensor with no sample after the frame time
 * holds its last value (HELD); without data for stale_after_s it is STALE. */
#ifndef MOCAP_FRAME_ASSEMBLER_H
#define MOCAP_FRAME_ASSEMBLER_H

#include <stdint.h>
#include "conditioning.h"
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define ASSEMBLER_HISTORY 32  /* samples kept per sensor (0.32 s at 100 Hz) */

/* One synchronised frame of raw (uncalibrated) sensor data. */
typedef struct raw_frame {
    uint64_t sequence;
    double t;                       /* frame time, session clock */
    uint32_t fresh_mask;            /* sensor had samples bracketing t */
    uint32_t valid_mask;            /* sensor has ever produced a sample */
    uint32_t stale_mask;            /* newest sample older than stale_after_s at t */
    double quat[MOCAP_MAX_SENSORS][4];        /* sensor -> world */
    double force_world[MOCAP_MAX_SENSORS][3]; /* specific force, world frame, m/s^2 */
    double gyr[MOCAP_MAX_SENSORS][3];         /* rad/s, sensor frame */
    double age[MOCAP_MAX_SENSORS];            /* t - newest sample time (>= 0) */
    uint32_t node_id[MOCAP_MAX_SENSORS];
} raw_frame;

typedef struct sensor_track {
    imu_sample samples[ASSEMBLER_HISTORY]; /* ring, oldest at head */
    uint32_t head;
    uint32_t count;
    int seen;
} sensor_track;

typedef struct frame_assembler {
    double period;
    double hold_latency;
    double stale_after;
    int started;
    double next_t;      /* time of the next frame to emit */
    double resume_t;    /* when the grid last (re)started: after a silence sensors resume one by
                         * one, so until resume_t + stale_after even stale sensors are waited for */
    uint64_t sequence;
    uint64_t out_of_order; /* samples older than the sensor's newest, dropped */
    sensor_track tracks[MOCAP_MAX_SENSORS];
} frame_assembler;

void assembler_init(frame_assembler *a, double rate_hz, double hold_latency_s, double stale_after_s);
/* Add a sample (s->segment in [0, MOCAP_MAX_SENSORS), s->t increasing per sensor). */
void assembler_push(frame_assembler *a, const imu_sample *s);
/* Whether a sample of segment at time t would be taken (newer than the sensor's newest). */
int assembler_is_newer(const frame_assembler *a, int segment, double t);
/* Emit the next frame if it is due given the data so far and the current session time now_s:
 * due when every valid sensor has a sample at or after next_t, or when now_s >= next_t +
 * hold_latency and some sensor is not stale. A sensor stale for longer than stale_after since the
 * grid (re)started is taken as gone and not waited for, so a dead sensor adds no latency. When every sensor is stale the frame grid jumps to
 * the first new sample instead of emitting frames of held data. Returns 1 and fills out when a
 * frame was emitted, 0 otherwise; call repeatedly until it returns 0. */
int assembler_next(frame_assembler *a, double now_s, raw_frame *out);

#ifdef __cplusplus
}
#endif
#endif
