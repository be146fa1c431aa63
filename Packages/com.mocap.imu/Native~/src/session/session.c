/* The session: a reader thread per device -> byte ring -> processing thread (pipeline) ->
 * frame ring -> the consumer's poll/drain calls. Rings are lock-free SPSC; the mutex only
 * guards rare control traffic (calibration requests, stats and report snapshots). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_file.h"
#include "error.h"
#include "mocap_imu.h"
#include "pipeline.h"
#include "segments.h"
#include "session_internal.h"
#include "platform.h"
#include "spsc_ring.h"
#include "transport.h"

#define BYTE_CHUNK_CAPACITY 4096
#define BYTE_RING_CHUNKS 256            /* 1 MiB of input in flight */
#define FRAME_RING_FRAMES 1024          /* 17 s at 60 Hz for a consumer that drains rarely */
#define READ_TIMEOUT_MS 50              /* bounds how long a stop request waits on a read */
#define RECONNECT_INTERVAL_MS 250
#define IDLE_SLEEP_MS 1

typedef struct byte_chunk {
    int64_t receive_ns;
    uint32_t length;
    uint32_t end_of_stream;
    uint8_t data[BYTE_CHUNK_CAPACITY];
} byte_chunk;

#define PENDING_CALIBRATION_REQUESTS 8

struct mocap_session {
    mocap_session_config config;
    transport *source;
    capture_writer *capture;
    pipeline *pipe;
    spsc_ring bytes;
    spsc_ring frames;
    /* Every frame is also published here: the newest one, for poll_latest, even while the
     * ring is full after a long pause of the consumer (the ring keeps the oldest). */
    triple_buffer newest_frame;
    mocap_thread *reader;
    mocap_thread *processor;
    int started;                /* under lock: start() was called (threads exist or starting) */
    int stopped;                /* under lock: mocap_session_stop ran (threads joined, capture closed) */
    int replay;                 /* data time, not the wall clock, drives frames */
    int replay_fast;            /* replay as fast as possible: back-pressure instead of dropping */

    mocap_atomic_int stop;
    mocap_atomic_int connection_state;
    mocap_atomic_int processing_done;
    mocap_atomic_int reader_done;   /* the reader thread returned (or never ran) */
    mocap_atomic_u64 bytes_received;
    mocap_atomic_u64 bytes_dropped;
    mocap_atomic_u64 frames_dropped;
    mocap_atomic_u64 reconnects;
    mocap_atomic_u64 replay_chunks_skipped;
    mocap_atomic_int replay_tail_damaged;

    /* Guarded by lock. */
    mocap_mutex *lock;
    calibration_request pending[PENDING_CALIBRATION_REQUESTS]; /* not yet handed to the pipeline */
    uint32_t pending_count;
    uint32_t pipeline_queued;   /* steps queued inside the pipeline, as of the last snapshot */
    int calibration_set_pending;
    mocap_calibration calibration_to_set;
    mocap_calibration calibration_snapshot;
    mocap_calibration_report report_snapshot;
    mocap_calibration_report step_report_snapshot[MOCAP_CALIBRATION_HEADING_RESET + 1];
    mocap_session_stats stats_snapshot;
    char async_error[256];
    char capture_error_text[200]; /* why the recording failed (async_error may move on) */

    /* Consumer side only. latest is the newest frame handed out by poll or drain: frames with
     * its sequence or an older one are not handed out again. */
    int have_latest;
    mocap_frame latest;
};

/* ---------------------------------------------------------------------------------------- */

mocap_status mocap_config_defaults(mocap_session_config *c)
{
    if (!c) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "config is NULL");
    memset(c, 0, sizeof *c);
    c->struct_size = sizeof *c;
    c->source_kind = MOCAP_SOURCE_SERIAL;
    c->baud = 460800;
    c->sensor_count = segments_default_set(c->sensor_segments, c->node_ids);
    c->imusol_layout = MOCAP_IMUSOL_AUTO;
    c->world_frame = MOCAP_WORLD_NWU;
    c->output_rate_hz = 60.0f;
    c->hold_latency_s = 0.05f;
    c->stale_after_s = 0.25f;
    c->kalman_process_noise = (float)KALMAN_DEFAULT_PROCESS_NOISE;
    c->kalman_measurement_noise = (float)KALMAN_DEFAULT_MEASUREMENT_NOISE;
    c->replay_realtime = 0;
    c->replay_speed = 1.0f;
    c->auto_reconnect = 1;
    return MOCAP_OK;
}

static void set_async_error(mocap_session *s, const char *text)
{
    mocap_mutex_lock(s->lock);
    snprintf(s->async_error, sizeof s->async_error, "%s", text);
    mocap_mutex_unlock(s->lock);
}

/* ---------------------------------------------------------------------------------------- */
/* Reader thread: device -> byte ring.                                                        */

static void queue_end_of_stream(mocap_session *s)
{
    while (!mocap_atomic_load_int(&s->stop)) {
        byte_chunk *end = (byte_chunk *)spsc_ring_reserve(&s->bytes);
        if (end) {
            end->length = 0;
            end->end_of_stream = 1;
            end->receive_ns = 0;
            spsc_ring_commit(&s->bytes);
            return;
        }
        mocap_sleep_ms(IDLE_SLEEP_MS);
    }
}

/* A replay passes over damaged chunks as it must (a crash-damaged capture is still worth
 * replaying), so the stats are where a consumer learns that the frames miss part of the file. */
static void note_source_damage(mocap_session *s)
{
    if (!s->source->ops->damage) return;
    uint64_t skipped = 0;
    int32_t tail = 0;
    s->source->ops->damage(s->source, &skipped, &tail);
    mocap_atomic_store_u64(&s->replay_chunks_skipped, skipped);
    mocap_atomic_store_int(&s->replay_tail_damaged, tail);
}

static void reader_loop(mocap_session *s)
{
    uint8_t overflow[BYTE_CHUNK_CAPACITY];
    char error_text[256];
    int connected = 1;

    while (!mocap_atomic_load_int(&s->stop)) {
        if (!connected) {
            mocap_status st = transport_reopen(s->source);
            if (st == MOCAP_OK) {
                connected = 1;
                mocap_atomic_add_u64(&s->reconnects, 1);
                mocap_atomic_store_int(&s->connection_state, MOCAP_CONNECTION_CONNECTED);
                continue;
            }
            /* Why the device went away, then why it cannot be opened again yet (gone from the
             * system, busy, no permission): the second is what a user can act on. */
            char reopen_text[240], combined[256];
            mocap_copy_error(reopen_text, sizeof reopen_text);
            snprintf(combined, sizeof combined, "reconnecting: %s", reopen_text);
            /* The loss's own text only where it fits: long port paths fill the line. */
            const size_t used = strlen(combined);
            if (used + 16 < sizeof combined)
                snprintf(combined + used, sizeof combined - used, " (lost: %.*s)",
                         (int)(sizeof combined - used - 10), error_text);
            set_async_error(s, combined);
            for (int waited = 0; waited < RECONNECT_INTERVAL_MS && !mocap_atomic_load_int(&s->stop);
                 waited += 10)
                mocap_sleep_ms(10);
            continue;
        }

        byte_chunk *chunk = (byte_chunk *)spsc_ring_reserve(&s->bytes);
        if (!chunk && s->replay_fast) {
            mocap_sleep_ms(IDLE_SLEEP_MS); /* processing is behind: wait, lose nothing */
            continue;
        }
        uint8_t *target = chunk ? chunk->data : overflow;
        size_t got = 0;
        int64_t receive_ns = 0;
        mocap_status st = transport_read(s->source, target, BYTE_CHUNK_CAPACITY, READ_TIMEOUT_MS,
                                         &got, &receive_ns);
        note_source_damage(s);
        if (st == MOCAP_OK) {
            mocap_atomic_add_u64(&s->bytes_received, got);
            if (chunk) {
                chunk->receive_ns = receive_ns;
                chunk->length = (uint32_t)got;
                chunk->end_of_stream = 0;
                spsc_ring_commit(&s->bytes);
            } else {
                mocap_atomic_add_u64(&s->bytes_dropped, got);
            }
        } else if (st == MOCAP_ERR_TIMEOUT) {
            continue;
        } else if (st == MOCAP_ERR_END_OF_STREAM) {
            queue_end_of_stream(s);
            return;
        } else {
            mocap_copy_error(error_text, sizeof error_text);
            set_async_error(s, error_text);
            if (s->config.source_kind == MOCAP_SOURCE_REPLAY) {
                /* A capture file that stops reading (a removed drive, a network share gone)
                 * cannot come back: end the stream there, so that the consumers drain what was
                 * read and see the end instead of waiting forever. last_error says why. */
                queue_end_of_stream(s);
                return;
            }
            mocap_atomic_store_int(&s->connection_state, MOCAP_CONNECTION_DISCONNECTED);
            if (!s->config.auto_reconnect) return;
            connected = 0;
        }
    }
}

static void reader_main(void *arg)
{
    mocap_session *s = (mocap_session *)arg;
    reader_loop(s);
    mocap_atomic_store_int(&s->reader_done, 1);
}

/* ---------------------------------------------------------------------------------------- */
/* Processing thread: byte ring -> pipeline -> frame ring.                                    */

static void deliver_frame(void *user, const mocap_frame *frame)
{
    mocap_session *s = (mocap_session *)user;
    *(mocap_frame *)triple_buffer_write_slot(&s->newest_frame) = *frame;
    triple_buffer_publish(&s->newest_frame);
    for (;;) {
        mocap_frame *slot = (mocap_frame *)spsc_ring_reserve(&s->frames);
        if (slot) {
            *slot = *frame;
            spsc_ring_commit(&s->frames);
            return;
        }
        /* Full. A fast replay waits for the consumer (nothing is lost); live data cannot wait. */
        if (!s->replay_fast || mocap_atomic_load_int(&s->stop)) {
            mocap_atomic_add_u64(&s->frames_dropped, 1);
            return;
        }
        mocap_sleep_ms(IDLE_SLEEP_MS);
    }
}

/* Hands waiting calibration requests to the pipeline and copies its reports out. s->lock held.
 * Runs on the processing thread, or on an API thread while no processing thread exists. */
static void publish_snapshots_locked(mocap_session *s)
{
    pipeline *p = s->pipe;
    uint32_t handed = 0;
    while (handed < s->pending_count &&
           pipeline_calibration_schedule(p, s->pending[handed].step, s->pending[handed].start_s,
                                         s->pending[handed].duration_s) == MOCAP_OK)
        ++handed;
    if (handed > 0) {
        memmove(&s->pending[0], &s->pending[handed], (s->pending_count - handed) * sizeof s->pending[0]);
        s->pending_count -= handed;
    }
    if (s->calibration_set_pending) {
        p->calibration = s->calibration_to_set;
        s->calibration_set_pending = 0;
    }
    s->pipeline_queued = p->queued;
    s->calibration_snapshot = p->calibration;
    s->report_snapshot = p->report;
    memcpy(s->step_report_snapshot, p->step_reports, sizeof s->step_report_snapshot);
    /* Requests still waiting here are not visible in the pipeline's reports yet. */
    for (uint32_t i = 0; i < s->pending_count; ++i) {
        mocap_calibration_report *r = &s->step_report_snapshot[s->pending[i].step];
        memset(r, 0, sizeof *r);
        r->step = s->pending[i].step;
        r->state = MOCAP_CALIBRATION_WAITING;
        r->seconds_remaining = s->pending[i].duration_s;
    }
    mocap_session_stats *st = &s->stats_snapshot;
    st->frames_decoded = p->decoder.stats.frames_ok;
    st->crc_failures = p->decoder.stats.crc_failures;
    st->bytes_skipped = p->decoder.stats.bytes_skipped;
    st->unknown_packets = p->decoder.stats.unknown_tags;
    st->samples_decoded = p->counters.samples_decoded;
    st->samples_rejected = p->counters.samples_rejected;
    st->frames_emitted = p->counters.frames_emitted;
    st->sensors_seen_mask = p->counters.sensors_seen_mask;
    if (s->capture) st->capture_bytes_written = capture_writer_bytes_written(s->capture);
}

static void publish_snapshots(mocap_session *s)
{
    mocap_mutex_lock(s->lock);
    publish_snapshots_locked(s);
    mocap_mutex_unlock(s->lock);
}

/* The capture's first failure (mocap_last_error holds its text) into the stats. Later failures
 * of a writer that already failed only repeat the first. */
static void note_capture_failure(mocap_session *s, mocap_status status)
{
    mocap_mutex_lock(s->lock);
    if (s->stats_snapshot.capture_error == MOCAP_OK) {
        mocap_copy_error(s->capture_error_text, sizeof s->capture_error_text);
        s->stats_snapshot.capture_error = status;
        snprintf(s->async_error, sizeof s->async_error, "recording stopped: %s",
                 s->capture_error_text);
    }
    mocap_mutex_unlock(s->lock);
}

static void record_capture_error(mocap_session *s, mocap_status status)
{
    note_capture_failure(s, status);
    /* Processing goes on without the recording: losing live data for a full disk is worse. */
    capture_writer_close(s->capture);
    s->capture = NULL;
}

static void processor_main(void *arg)
{
    mocap_session *s = (mocap_session *)arg;
    int ended = 0;
    int64_t last_snapshot_ns = 0;
    publish_snapshots(s);
    while (!ended) {
        int worked = 0;
        const byte_chunk *chunk;
        while ((chunk = (const byte_chunk *)spsc_ring_peek(&s->bytes)) != NULL) {
            if (chunk->end_of_stream) {
                ended = 1;
                spsc_ring_release(&s->bytes);
                break;
            }
            if (s->capture) {
                mocap_status st = capture_writer_append(s->capture, chunk->receive_ns, chunk->data,
                                                        chunk->length);
                if (st != MOCAP_OK) record_capture_error(s, st);
            }
            pipeline_feed(s->pipe, chunk->data, chunk->length, chunk->receive_ns);
            spsc_ring_release(&s->bytes);
            worked = 1;
            /* Keep calibration requests and stats responsive during a fast replay. */
            int64_t now = mocap_monotonic_ns();
            if (now - last_snapshot_ns > 5000000) {
                publish_snapshots(s);
                last_snapshot_ns = now;
            }
        }
        int64_t now_ns = mocap_monotonic_ns();
        /* Live: let wall time release frames that late sensors held up. A replay (paced or not)
         * runs on its recorded timeline, where only data moves time on. */
        if (!s->replay) pipeline_advance(s->pipe, now_ns);
        if (s->capture) {
            mocap_status st = capture_writer_poll(s->capture, now_ns);
            if (st != MOCAP_OK) record_capture_error(s, st);
        }
        publish_snapshots(s);
        last_snapshot_ns = now_ns;
        if (ended) {
            /* Let the frames that waited for late sensors out, then report the end. */
            /* Saturating: a damaged capture can hold receive times next to INT64_MAX. */
            const int64_t newest = s->pipe->newest_receive_ns;
            pipeline_finish(s->pipe, newest > INT64_MAX - 2000000000LL ? INT64_MAX
                                                                       : newest + 2000000000LL);
            publish_snapshots(s);
            mocap_atomic_store_int(&s->connection_state, MOCAP_CONNECTION_ENDED);
            break;
        }
        /* On stop, the bytes the reader committed before it returned are still recorded and
         * processed: whatever was read from the port reaches the capture. */
        if (mocap_atomic_load_int(&s->stop) && mocap_atomic_load_int(&s->reader_done) &&
            spsc_ring_size(&s->bytes) == 0)
            break;
        if (!worked) mocap_sleep_ms(IDLE_SLEEP_MS);
    }
    if (s->capture) {
        mocap_status st = capture_writer_flush(s->capture);
        if (st != MOCAP_OK) record_capture_error(s, st);
    }
    mocap_atomic_store_int(&s->processing_done, 1);
}

/* ---------------------------------------------------------------------------------------- */
/* Public API                                                                                 */

static void session_free(mocap_session *s)
{
    if (!s) return;
    if (s->capture) capture_writer_close(s->capture);
    if (s->source) transport_close(s->source);
    spsc_ring_destroy(&s->bytes);
    spsc_ring_destroy(&s->frames);
    triple_buffer_destroy(&s->newest_frame);
    if (s->lock) mocap_mutex_destroy(s->lock);
    free(s->pipe);
    free(s);
}

static int64_t live_clock(void) { return mocap_monotonic_ns(); }

mocap_status mocap_session_open(const mocap_session_config *config, mocap_session **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "out is NULL");
    *out = NULL;
    mocap_status st = pipeline_validate_config(config);
    if (st != MOCAP_OK) return st;

    mocap_session *s = (mocap_session *)calloc(1, sizeof *s);
    if (!s) return mocap_fail(MOCAP_ERR_NO_MEMORY, "out of memory allocating a session");
    s->config = *config;
    s->pipe = (pipeline *)calloc(1, sizeof *s->pipe);
    if (!s->pipe || mocap_mutex_create(&s->lock) != 0 ||
        spsc_ring_init(&s->bytes, sizeof(byte_chunk), BYTE_RING_CHUNKS) != 0 ||
        spsc_ring_init(&s->frames, sizeof(mocap_frame), FRAME_RING_FRAMES) != 0 ||
        triple_buffer_init(&s->newest_frame, sizeof(mocap_frame)) != 0) {
        session_free(s);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "out of memory allocating session buffers");
    }

    switch (config->source_kind) {
    case MOCAP_SOURCE_SERIAL:
        st = transport_open_serial(config->path, config->baud, &s->source);
        break;
    case MOCAP_SOURCE_HID:
        st = transport_open_hid(config->path, config->hid_vendor_id, config->hid_product_id,
                                &s->source);
        break;
    case MOCAP_SOURCE_REPLAY:
        if (!(config->replay_speed > 0.0f) || !isfinite(config->replay_speed)) {
            session_free(s);
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "replay_speed must be positive");
        }
        st = transport_open_replay(config->path, config->replay_realtime, config->replay_speed,
                                   &s->source);
        s->replay = 1;
        s->replay_fast = !config->replay_realtime;
        break;
    default:
        session_free(s);
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "source_kind %d is unknown",
                          config->source_kind);
    }
    if (st != MOCAP_OK) {
        session_free(s); /* keeps the transport's error text: nothing below fails */
        return st;
    }
    if (config->capture_path[0] != '\0') {
        st = capture_writer_open_with_source(config->capture_path, s->source->description,
                                            &s->capture);
        if (st != MOCAP_OK) {
            session_free(s);
            return st;
        }
    }
    pipeline_init(s->pipe, config, deliver_frame, s);
    if (!s->replay) s->pipe->clock_ns = live_clock;
    mocap_atomic_store_int(&s->connection_state, MOCAP_CONNECTION_CONNECTED);
    publish_snapshots(s);
    *out = s;
    return MOCAP_OK;
}

mocap_status mocap_session_start(mocap_session *s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session is NULL");
    mocap_mutex_lock(s->lock);
    int already = s->started, stopped = s->stopped;
    if (!stopped) s->started = 1; /* before the threads exist: see mocap_calibration_schedule */
    mocap_mutex_unlock(s->lock);
    if (stopped)
        return mocap_fail(MOCAP_ERR_STATE, "session was stopped; open a new one to start again");
    if (already) return mocap_fail(MOCAP_ERR_STATE, "session already started");
    const char *failed = NULL;
    if (mocap_thread_start(&s->processor, processor_main, s, "mocap-process") != 0) {
        failed = "could not start the processing thread";
    } else if (mocap_thread_start(&s->reader, reader_main, s, "mocap-reader") != 0) {
        failed = "could not start the reader thread";
        mocap_atomic_store_int(&s->reader_done, 1);
        mocap_atomic_store_int(&s->stop, 1);
        mocap_thread_join(s->processor);
        s->processor = NULL;
    }
    if (failed) {
        /* Back to the unstarted state, so that a later start() can succeed. */
        mocap_atomic_store_int(&s->stop, 0);
        mocap_atomic_store_int(&s->processing_done, 0);
        mocap_atomic_store_int(&s->reader_done, 0);
        mocap_mutex_lock(s->lock);
        s->started = 0;
        mocap_mutex_unlock(s->lock);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "%s", failed);
    }
    return MOCAP_OK;
}

mocap_status mocap_session_stop(mocap_session *s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session is NULL");
    mocap_mutex_lock(s->lock);
    int first = !s->stopped;
    s->stopped = 1;
    mocap_mutex_unlock(s->lock);
    if (first) {
        mocap_atomic_store_int(&s->stop, 1);
        if (s->reader) mocap_thread_join(s->reader);
        if (s->processor) mocap_thread_join(s->processor);
        s->reader = s->processor = NULL;
        /* No thread is left: the capture is this thread's. Flush, count, then close, since
         * some file systems (NFS, FUSE) report a deferred write error only at close. */
        if (s->capture) {
            mocap_status st = capture_writer_flush(s->capture);
            if (st != MOCAP_OK) {
                record_capture_error(s, st);
            } else {
                capture_writer *w = s->capture;
                s->capture = NULL;
                const uint64_t written = capture_writer_bytes_written(w);
                st = capture_writer_close(w);
                mocap_mutex_lock(s->lock);
                s->stats_snapshot.capture_bytes_written = written;
                mocap_mutex_unlock(s->lock);
                if (st != MOCAP_OK) note_capture_failure(s, st);
            }
        }
    }
    mocap_mutex_lock(s->lock);
    const mocap_status capture_status = (mocap_status)s->stats_snapshot.capture_error;
    mocap_mutex_unlock(s->lock);
    if (capture_status != MOCAP_OK)
        return mocap_fail(capture_status, "%s", s->capture_error_text);
    return MOCAP_OK;
}

void mocap_session_close(mocap_session *s)
{
    if (!s) return;
    mocap_session_stop(s);
    session_free(s);
}

static mocap_status end_or_no_data(mocap_session *s)
{
    if (mocap_atomic_load_int(&s->processing_done) &&
        mocap_atomic_load_int(&s->connection_state) == MOCAP_CONNECTION_ENDED &&
        spsc_ring_size(&s->frames) == 0)
        return mocap_fail(MOCAP_ERR_END_OF_STREAM, "replay finished");
    return MOCAP_ERR_NO_DATA;
}

/* A frame the consumer has not been handed yet (poll and drain may both have run). */
static int frame_is_new(const mocap_session *s, const mocap_frame *f)
{
    return !s->have_latest || f->sequence > s->latest.sequence;
}

static void hand_out_frame(mocap_session *s, const mocap_frame *f)
{
    s->latest = *f;
    s->have_latest = 1;
}

mocap_status mocap_session_poll_latest(mocap_session *s, mocap_frame *out)
{
    if (!s || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session or out is NULL");
    int got = 0;
    const mocap_frame *f;
    while ((f = (const mocap_frame *)spsc_ring_peek(&s->frames)) != NULL) {
        if (frame_is_new(s, f)) {
            hand_out_frame(s, f);
            got = 1;
        }
        spsc_ring_release(&s->frames);
    }
    /* After a long pause the ring holds the oldest frames and newer ones were dropped; the
     * newest is here. Taken after the ring, so it is at least as new as what the ring held. */
    const mocap_frame *newest = (const mocap_frame *)triple_buffer_take(&s->newest_frame);
    if (newest && frame_is_new(s, newest)) {
        hand_out_frame(s, newest);
        got = 1;
    }
    if (!got) return end_or_no_data(s);
    *out = s->latest;
    return MOCAP_OK;
}

mocap_status mocap_session_drain(mocap_session *s, mocap_frame *out, uint32_t capacity,
                                 uint32_t *count)
{
    if (!s || !out || !count)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session, out or count is NULL");
    uint32_t n = 0;
    while (n < capacity && spsc_ring_pop(&s->frames, &out[n]) == 0) {
        if (!frame_is_new(s, &out[n])) continue; /* a poll already handed it out */
        hand_out_frame(s, &out[n]);
        ++n;
    }
    *count = n;
    if (n == 0) return end_or_no_data(s);
    return MOCAP_OK;
}

mocap_status mocap_session_get_stats(mocap_session *s, mocap_session_stats *out)
{
    if (!s || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session or out is NULL");
    mocap_mutex_lock(s->lock);
    *out = s->stats_snapshot;
    snprintf(out->last_error, sizeof out->last_error, "%s", s->async_error);
    mocap_mutex_unlock(s->lock);
    out->bytes_received = mocap_atomic_load_u64(&s->bytes_received);
    out->bytes_dropped = mocap_atomic_load_u64(&s->bytes_dropped);
    out->frames_dropped = mocap_atomic_load_u64(&s->frames_dropped);
    out->reconnects = mocap_atomic_load_u64(&s->reconnects);
    out->replay_chunks_skipped = mocap_atomic_load_u64(&s->replay_chunks_skipped);
    out->replay_tail_damaged = mocap_atomic_load_int(&s->replay_tail_damaged);
    out->connection_state = mocap_atomic_load_int(&s->connection_state);
    return MOCAP_OK;
}

mocap_status mocap_calibration_schedule(mocap_session *s, int32_t step, double start_s,
                                        float duration_s)
{
    if (!s) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session is NULL");
    if (step < MOCAP_CALIBRATION_HEADING || step > MOCAP_CALIBRATION_HEADING_RESET)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration step %d is unknown", step);
    if (!(duration_s >= 0.2f && duration_s <= 15.0f))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "calibration duration %g s is outside 0.2..15 s", (double)duration_s);
    if (!isfinite(start_s))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration start time is not finite");
    mocap_mutex_lock(s->lock);
    /* The limit counts every step still waiting, here or already inside the pipeline. */
    if (s->pending_count + s->pipeline_queued >= PENDING_CALIBRATION_REQUESTS) {
        mocap_mutex_unlock(s->lock);
        return mocap_fail(MOCAP_ERR_STATE, "%d calibration steps are already waiting",
                          PENDING_CALIBRATION_REQUESTS);
    }
    calibration_request r = {step, start_s, duration_s};
    s->pending[s->pending_count++] = r;
    /* Before start() no thread would pick the request up, so publish it here. started is read
     * and written under the lock, so this never overlaps the processing thread, which only
     * exists once started is set. */
    if (!s->started) publish_snapshots_locked(s);
    mocap_mutex_unlock(s->lock);
    return MOCAP_OK;
}

mocap_status mocap_calibration_get_report(mocap_session *s, mocap_calibration_report *out)
{
    if (!s || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session or out is NULL");
    mocap_mutex_lock(s->lock);
    *out = s->report_snapshot;
    mocap_mutex_unlock(s->lock);
    return MOCAP_OK;
}

mocap_status mocap_calibration_get_step_report(mocap_session *s, int32_t step,
                                               mocap_calibration_report *out)
{
    if (!s || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session or out is NULL");
    if (step < MOCAP_CALIBRATION_HEADING || step > MOCAP_CALIBRATION_HEADING_RESET)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration step %d is unknown", step);
    mocap_mutex_lock(s->lock);
    *out = s->step_report_snapshot[step];
    mocap_mutex_unlock(s->lock);
    return MOCAP_OK;
}

mocap_status mocap_calibration_get(mocap_session *s, mocap_calibration *out)
{
    if (!s || !out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session or out is NULL");
    mocap_mutex_lock(s->lock);
    *out = s->calibration_set_pending ? s->calibration_to_set : s->calibration_snapshot;
    mocap_mutex_unlock(s->lock);
    return MOCAP_OK;
}

static mocap_status check_calibration(const mocap_calibration *cal)
{
    if (cal->struct_size != sizeof(mocap_calibration))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "calibration struct_size is %u, this library expects %u",
                          (unsigned)cal->struct_size, (unsigned)sizeof(mocap_calibration));
    /* What save and load accept, nothing else (NaN/Inf included): a scaled matrix would flag
     * frames calibrated while distorting every bone, and the calibration in use could not be
     * saved. */
    char why[160];
    if (calib_check(cal, why, sizeof why) != 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration refused: %s", why);
    return MOCAP_OK;
}

/* cal's entries in the session's sensor order, matched by segment. */
static mocap_status calibration_for_session(const mocap_session *s, const mocap_calibration *cal,
                                            mocap_calibration *out)
{
    const mocap_session_config *c = &s->config;
    calib_identity(out, c->sensor_count, c->sensor_segments);
    int shared = 0;
    for (uint32_t i = 0; i < c->sensor_count; ++i) {
        int e = segments_index_of(cal->segments, cal->sensor_count, c->sensor_segments[i]);
        if (e < 0) continue;
        shared = 1;
        memcpy(out->world_to_model[i], cal->world_to_model[e], sizeof out->world_to_model[i]);
        memcpy(out->sensor_to_bone[i], cal->sensor_to_bone[e], sizeof out->sensor_to_bone[i]);
        memcpy(out->acceleration_offset[i], cal->acceleration_offset[e],
               sizeof out->acceleration_offset[i]);
        if (cal->valid_mask & (1u << e)) out->valid_mask |= 1u << i;
        if (cal->heading_mask & (1u << e)) out->heading_mask |= 1u << i;
    }
    if (!shared)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "calibration refused: none of its %u sensors is on a segment of this "
                          "session", (unsigned)cal->sensor_count);
    return MOCAP_OK;
}

mocap_status mocap_calibration_set(mocap_session *s, const mocap_calibration *cal)
{
    if (!s || !cal) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "session or calibration is NULL");
    mocap_status st = check_calibration(cal);
    if (st != MOCAP_OK) return st;
    mocap_calibration mapped;
    st = calibration_for_session(s, cal, &mapped);
    if (st != MOCAP_OK) return st;
    mocap_mutex_lock(s->lock);
    s->calibration_to_set = mapped;
    s->calibration_set_pending = 1;
    if (!s->started) publish_snapshots_locked(s); /* as in mocap_calibration_schedule */
    mocap_mutex_unlock(s->lock);
    return MOCAP_OK;
}

mocap_status mocap_calibration_save(const mocap_calibration *cal, const char *path)
{
    if (!cal || !path) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "calibration or path is NULL");
    mocap_status st = check_calibration(cal);
    if (st != MOCAP_OK) return st;
    return calib_save(cal, path);
}

mocap_status mocap_calibration_load(const char *path, mocap_calibration *out)
{
    if (!out || !path) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "path or out is NULL");
    return calib_load(path, out);
}

/* ---------------------------------------------------------------------------------------- */
/* Internal accessors (session_internal.h)                                                    */

const mocap_session_config *session_config(const mocap_session *s) { return s ? &s->config : NULL; }
