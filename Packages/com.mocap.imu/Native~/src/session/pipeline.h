/* The processing chain, single-threaded and deterministic: bytes -> HiPNUC frames -> conditioned
 * samples -> Kalman-filtered world specific force -> synchronised frames -> calibration. The
 * session runs one pipeline on its processing thread; tests and the CLI can drive one directly. */
#ifndef MOCAP_PIPELINE_H
#define MOCAP_PIPELINE_H

#include <stdint.h>
#include "calibration.h"
#include "conditioning.h"
#include "frame_assembler.h"
#include "hipnuc_decoder.h"
#include "kalman.h"
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Calibration steps can be queued (e.g. heading then T-pose of a replay's prelude, scheduled
 * before the replay starts, since a fast replay would outrun a caller reacting to results). */
#define PIPELINE_CALIBRATION_QUEUE 8

typedef struct calibration_request {
    int32_t step;
    double start_s;
    float duration_s;
} calibration_request;

/* Called for every output frame; the frame is only valid during the call. */
typedef void (*pipeline_frame_fn)(void *user, const mocap_frame *frame);

typedef struct pipeline_counters {
    uint64_t samples_decoded;
    uint64_t samples_rejected;
    uint64_t unknown_nodes;
    uint64_t frames_emitted;
    uint32_t sensors_seen_mask;
} pipeline_counters;

typedef struct pipeline {
    mocap_session_config config;
    int node_to_segment[256];          /* node id -> sensor index (config order), -1 if unmapped */
    hipnuc_decoder decoder;
    time_unwrapper unwrap[MOCAP_MAX_SENSORS];
    clock_mapper clock[MOCAP_MAX_SENSORS];
    double untimed_t[MOCAP_MAX_SENSORS]; /* last time given to a sample without a sensor time */
    accel_kalman kalman[MOCAP_MAX_SENSORS];
    frame_assembler assembler;
    calib_accumulator calib;
    mocap_calibration calibration;
    mocap_calibration_report report;   /* the active step, or the last one finished */
    mocap_calibration_report step_reports[MOCAP_CALIBRATION_HEADING_RESET + 1]; /* last of each */
    calibration_request queue[PIPELINE_CALIBRATION_QUEUE];
    uint32_t queued;
    pipeline_counters counters;
    double now_s;                      /* newest receive time seen, session clock */
    int64_t newest_receive_ns;
    pipeline_frame_fn on_frame;
    void *user;
    /* Clock stamped into mocap_frame.emitted_ns; NULL stamps the newest receive time (replay
     * as fast as possible, where wall time means nothing). */
    int64_t (*clock_ns)(void);
    raw_frame raw;                     /* scratch, reused */
    mocap_frame out;                   /* scratch, reused */
} pipeline;

/* The config must have been validated (pipeline_validate_config). */
void pipeline_init(pipeline *p, const mocap_session_config *config, pipeline_frame_fn on_frame,
                   void *user);
mocap_status pipeline_validate_config(const mocap_session_config *config);
/* Feed bytes received at receive_ns (session clock, ns) and emit the frames that became due. */
void pipeline_feed(pipeline *p, const uint8_t *data, size_t len, int64_t receive_ns);
/* End of input: decode whatever whole frames the decoder still holds (see hipnuc_decoder_flush),
 * then let the frames waiting for late sensors out, as if now_ns had been reached. */
void pipeline_finish(pipeline *p, int64_t now_ns);
/* Let session time pass without bytes (live: a timer tick; replay: the end of the file), so
 * frames waiting for late sensors are emitted with held values. */
void pipeline_advance(pipeline *p, int64_t now_ns);
/* Queue a calibration step (called on the pipeline's thread). It starts at start_s, or when the
 * steps before it have finished if that is later (start_s < 0: the next frame then). Returns
 * MOCAP_ERR_STATE when PIPELINE_CALIBRATION_QUEUE steps are already waiting. */
mocap_status pipeline_calibration_schedule(pipeline *p, int32_t step, double start_s,
                                           float duration_s);

#ifdef __cplusplus
}
#endif
#endif
