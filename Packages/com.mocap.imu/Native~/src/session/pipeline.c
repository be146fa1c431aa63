#include "pipeline.h"

#include <math.h>
#include <string.h>

#include "error.h"
#include "mocap_math.h"

static void on_decoded_frame(void *user, const hipnuc_frame *frame);
static void empty_report(const pipeline *p, mocap_calibration_report *r, int32_t step);

mocap_status pipeline_validate_config(const mocap_session_config *c)
{
    if (!c) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "config is NULL");
    if (c->struct_size != sizeof(mocap_session_config))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "config struct_size is %u, this library expects %u (binding out of date?)",
                          (unsigned)c->struct_size, (unsigned)sizeof(mocap_session_config));
    if (!(c->output_rate_hz >= 1.0f && c->output_rate_hz <= 1000.0f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "output_rate_hz %g is outside 1..1000",
                          (double)c->output_rate_hz);
    if (!(c->hold_latency_s >= 0.0f && c->hold_latency_s <= 1.0f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "hold_latency_s %g is outside 0..1",
                          (double)c->hold_latency_s);
    if (!(c->stale_after_s > 0.0f && c->stale_after_s <= 10.0f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "stale_after_s %g is outside (0, 10]",
                          (double)c->stale_after_s);
    if (!(c->kalman_process_noise > 0.0f) || !(c->kalman_measurement_noise > 0.0f) ||
        !isfinite(c->kalman_process_noise) || !isfinite(c->kalman_measurement_noise))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "Kalman noise parameters must be positive");
    if (c->imusol_layout < MOCAP_IMUSOL_AUTO || c->imusol_layout > MOCAP_IMUSOL_STATUS_WORD)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "imusol_layout %d is unknown", c->imusol_layout);
    if (c->world_frame != MOCAP_WORLD_NWU && c->world_frame != MOCAP_WORLD_ENU)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "world_frame %d is unknown", c->world_frame);
    if (c->sensor_count < 1 || c->sensor_count > MOCAP_MAX_SENSORS)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "sensor_count %u is outside 1..%d",
                          (unsigned)c->sensor_count, MOCAP_MAX_SENSORS);
    if (c->optional_mask >> c->sensor_count)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "optional_mask 0x%x names sensors beyond the %u configured",
                          (unsigned)c->optional_mask, (unsigned)c->sensor_count);
    for (uint32_t s = 0; s < c->sensor_count; ++s) {
        int32_t seg = c->sensor_segments[s];
        const char *name = mocap_segment_name(seg);
        if (!name)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "sensor %u: segment %d is not a known segment (0..%d)", (unsigned)s,
                              seg, mocap_segment_count() - 1);
        int id = c->node_ids[s];
        if (id < 0 || id > 255)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "node id %d for %s is outside 0..255",
                              id, name);
        for (uint32_t o = 0; o < s; ++o) {
            if (c->node_ids[o] == id)
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "node id %d is mapped to both %s and %s",
                                  id, mocap_segment_name(c->sensor_segments[o]), name);
            if (c->sensor_segments[o] == seg)
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                                  "segment %s is configured for two sensors (%u and %u)", name,
                                  (unsigned)o, (unsigned)s);
        }
    }
    if (memchr(c->path, '\0', sizeof c->path) == NULL ||
        memchr(c->capture_path, '\0', sizeof c->capture_path) == NULL)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "path is not NUL-terminated");
    return MOCAP_OK;
}

void pipeline_init(pipeline *p, const mocap_session_config *config, pipeline_frame_fn on_frame,
                   void *user)
{
    memset(p, 0, sizeof *p);
    p->config = *config;
    for (int i = 0; i < 256; ++i) p->node_to_segment[i] = -1;
    for (uint32_t s = 0; s < config->sensor_count; ++s)
        p->node_to_segment[config->node_ids[s]] = (int)s;
    hipnuc_decoder_init(&p->decoder, config->imusol_layout);
    for (int s = 0; s < MOCAP_MAX_SENSORS; ++s) {
        time_unwrapper_init(&p->unwrap[s]);
        clock_mapper_init(&p->clock[s]);
        p->untimed_t[s] = -INFINITY;
        accel_kalman_init(&p->kalman[s], config->kalman_process_noise,
                          config->kalman_measurement_noise);
    }
    assembler_init(&p->assembler, config->output_rate_hz, config->hold_latency_s,
                   config->stale_after_s);
    calib_init(&p->calib, config->sensor_count, config->sensor_segments, config->optional_mask);
    calib_identity(&p->calibration, config->sensor_count, config->sensor_segments);
    empty_report(p, &p->report, -1);
    p->report.state = MOCAP_CALIBRATION_IDLE;
    for (int i = 0; i <= MOCAP_CALIBRATION_HEADING_RESET; ++i) {
        empty_report(p, &p->step_reports[i], i);
        p->step_reports[i].state = MOCAP_CALIBRATION_IDLE;
    }
    p->on_frame = on_frame;
    p->user = user;
    p->now_s = -INFINITY;
}

/* An empty report of the session's sensors, so a waiting step already lists them. */
static void empty_report(const pipeline *p, mocap_calibration_report *r, int32_t step)
{
    memset(r, 0, sizeof *r);
    r->step = step;
    r->sensor_count = p->config.sensor_count;
    for (uint32_t s = 0; s < p->config.sensor_count; ++s)
        r->sensors[s].segment = p->config.sensor_segments[s];
}

static void begin_request(pipeline *p, const calibration_request *r)
{
    calib_begin(&p->calib, r->step, r->start_s, r->duration_s);
    empty_report(p, &p->report, r->step);
    p->report.state = MOCAP_CALIBRATION_WAITING;
    p->report.seconds_remaining = r->duration_s;
    p->step_reports[r->step] = p->report;
}

/* finished_t: the frame that ended the step before. A queued step whose window began before
 * that starts there instead, with its whole duration (mocap_calibration_schedule: it "starts
 * after it"); keeping its absolute window would shorten it or leave it no frame at all. */
static void start_next_request(pipeline *p, double finished_t)
{
    if (p->queued == 0) return;
    calibration_request next = p->queue[0];
    memmove(&p->queue[0], &p->queue[1], (p->queued - 1) * sizeof p->queue[0]);
    p->queued--;
    if (next.start_s >= 0.0 && next.start_s < finished_t) next.start_s = finished_t;
    begin_request(p, &next);
}

static void emit_due_frames(pipeline *p)
{
    while (assembler_next(&p->assembler, p->now_s, &p->raw)) {
        if (p->calib.step >= 0) {
            if (calib_add_frame(&p->calib, &p->raw)) {
                calib_finish(&p->calib, &p->calibration, &p->report);
                if (p->report.step >= 0 && p->report.step <= MOCAP_CALIBRATION_HEADING_RESET)
                    p->step_reports[p->report.step] = p->report;
                start_next_request(p, p->raw.t);
            } else {
                calib_progress(&p->calib, p->raw.t, &p->report);
                /* The step's own report follows it through collecting, not just its result. */
                if (p->report.step >= 0 && p->report.step <= MOCAP_CALIBRATION_HEADING_RESET)
                    p->step_reports[p->report.step] = p->report;
            }
        }
        calib_apply(&p->calibration, p->config.world_frame, p->config.optional_mask, &p->raw, &p->out);
        /* A sensor that never sent a sample still names the node it is configured for. */
        for (uint32_t s = 0; s < p->config.sensor_count; ++s)
            if (p->out.sensors[s].state == MOCAP_SENSOR_ABSENT)
                p->out.sensors[s].node_id = (uint32_t)p->config.node_ids[s];
        p->out.sequence = p->raw.sequence;
        p->out.time_s = p->raw.t;
        p->out.newest_receive_ns = p->newest_receive_ns;
        p->out.emitted_ns = p->clock_ns ? p->clock_ns() : p->newest_receive_ns;
        p->counters.frames_emitted++;
        if (p->on_frame) p->on_frame(p->user, &p->out);
    }
}

static void take_sample(pipeline *p, const hipnuc_sample *raw, double receive_s)
{
    int segment = raw->node_id < 256 ? p->node_to_segment[raw->node_id] : -1;
    if (segment < 0) {
        p->counters.unknown_nodes++;
        p->counters.samples_rejected++;
        return;
    }
    imu_sample s;
    if (condition_sample(raw, &s) != CONDITION_OK) {
        p->counters.samples_rejected++;
        return;
    }
    s.segment = segment;
    if (raw->fields & HIPNUC_FIELD_TIME) {
        double sensor_s = (double)time_unwrap_ms(&p->unwrap[segment], raw->time_ms) / 1000.0;
        s.t = clock_map(&p->clock[segment], sensor_s, receive_s);
    } else {
        /* No sensor time (older chained packets): every sample of one read shares the read's
         * receive time, and the assembler keeps only samples newer than the last. Spread them
         * 0.1 ms apart so that a read holding several samples of a sensor loses none. */
        s.t = receive_s > p->untimed_t[segment] ? receive_s : p->untimed_t[segment] + 1e-4;
        p->untimed_t[segment] = s.t;
    }
    if (!assembler_is_newer(&p->assembler, segment, s.t)) {
        /* A sample older than one already taken (a sensor clock that jumped back) would move
         * the filter and the frames back in time: refused, and counted. */
        p->counters.samples_rejected++;
        return;
    }
    /* Filtering in the world frame keeps the filter's smoothness assumption true while the
     * sensor turns: in the sensor frame gravity would swing between axes. */
    double r[9], force[3];
    quat_to_mat3(r, s.quat);
    mat3_apply(force, r, s.acc);
    accel_kalman_update(&p->kalman[segment], s.t, force, s.force_world);
    assembler_push(&p->assembler, &s);
    p->counters.samples_decoded++;
    p->counters.sensors_seen_mask |= 1u << segment;
}

typedef struct feed_context {
    pipeline *p;
    double receive_s;
} feed_context;

static void on_decoded_frame(void *user, const hipnuc_frame *frame)
{
    feed_context *ctx = (feed_context *)user;
    for (uint32_t i = 0; i < frame->sample_count; ++i)
        take_sample(ctx->p, &frame->samples[i], ctx->receive_s);
}

void pipeline_feed(pipeline *p, const uint8_t *data, size_t len, int64_t receive_ns)
{
    feed_context ctx = {p, (double)receive_ns * 1e-9};
    if (receive_ns > p->newest_receive_ns) p->newest_receive_ns = receive_ns;
    hipnuc_decoder_feed(&p->decoder, data, len, on_decoded_frame, &ctx);
    if (ctx.receive_s > p->now_s) p->now_s = ctx.receive_s;
    emit_due_frames(p);
}

void pipeline_advance(pipeline *p, int64_t now_ns)
{
    double now_s = (double)now_ns * 1e-9;
    if (now_s > p->now_s) p->now_s = now_s;
    emit_due_frames(p);
}

void pipeline_finish(pipeline *p, int64_t now_ns)
{
    feed_context ctx = {p, (double)p->newest_receive_ns * 1e-9};
    hipnuc_decoder_flush(&p->decoder, on_decoded_frame, &ctx);
    pipeline_advance(p, now_ns);
}

mocap_status pipeline_calibration_schedule(pipeline *p, int32_t step, double start_s,
                                           float duration_s)
{
    if (step < MOCAP_CALIBRATION_HEADING || step > MOCAP_CALIBRATION_HEADING_RESET)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration step %d is unknown", step);
    calibration_request r = {step, start_s, duration_s};
    if (p->calib.step < 0) {
        begin_request(p, &r);
        return MOCAP_OK;
    }
    if (p->queued >= PIPELINE_CALIBRATION_QUEUE)
        return mocap_fail(MOCAP_ERR_STATE, "%d calibration steps are already waiting",
                          PIPELINE_CALIBRATION_QUEUE);
    p->queue[p->queued++] = r;
    empty_report(p, &p->step_reports[step], step);
    p->step_reports[step].state = MOCAP_CALIBRATION_WAITING;
    p->step_reports[step].seconds_remaining = duration_s;
    return MOCAP_OK;
}
