/* A transport that plays a capture file back: either as fast as the reader thread asks, with
 * the recorded receive times, or paced like the original session on the live clock. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "capture_file.h"
#include "error.h"
#include "platform.h"
#include "transport.h"

typedef struct replay_transport {
    transport base; /* first, so a transport * is a replay_transport * */
    capture_reader *reader;
    int realtime;
    double speed;
    int64_t first_mono_ns;  /* live time the first record maps to: when it was read */
    int64_t first_record_ns;
    int have_first;
    /* The record being delivered: held while it is not yet due, or while a small cap makes
     * it come out in pieces. */
    const uint8_t *pending;
    size_t pending_len;
    size_t pending_off;
    int64_t pending_ns;     /* recorded receive time: the session's timeline in a replay */
    int64_t pending_due_ns; /* realtime: when the record is due on the monotonic clock */
    int ended;
} replay_transport;

static int64_t due_time(replay_transport *r, int64_t recorded_ns)
{
    if (!r->have_first) {
        /* Pace from the first read (the session's start), not from open: records recorded
         * within the gap between open and start would otherwise all be overdue at once. */
        r->first_mono_ns = mocap_monotonic_ns();
        r->first_record_ns = recorded_ns;
        r->have_first = 1;
    }
    /* Offsets from the first record keep the arithmetic exact over long captures. Taken in
     * double and capped (at ~127 years either way) because a damaged or hand-made capture can
     * hold any int64 times, whose difference would overflow. */
    const double cap = 4.0e18;
    double offset = ((double)recorded_ns - (double)r->first_record_ns) / r->speed;
    if (offset > cap) offset = cap;
    if (offset < -cap) offset = -cap;
    return r->first_mono_ns + (int64_t)llround(offset);
}

static mocap_status replay_read(transport *t, uint8_t *buf, size_t cap, int timeout_ms,
                                size_t *got, int64_t *receive_ns)
{
    replay_transport *r = (replay_transport *)t;
    if (!buf || cap == 0 || !got || !receive_ns)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "%s: read with no buffer",
                          r->base.description);
    *got = 0;
    if (r->ended) return MOCAP_ERR_END_OF_STREAM;

    if (!r->pending) {
        int64_t ns;
        const uint8_t *data;
        size_t len;
        /* Bounded like a device read, so the session's stop is seen between calls. */
        const int64_t deadline = mocap_monotonic_ns() + (int64_t)(timeout_ms > 0 ? timeout_ms : 1) * 1000000LL;
        mocap_status st = capture_reader_next_until(r->reader, deadline, &ns, &data, &len);
        if (st == MOCAP_ERR_TIMEOUT) return st;
        if (st == MOCAP_ERR_END_OF_STREAM) {
            r->ended = 1;
            return mocap_fail(MOCAP_ERR_END_OF_STREAM, "%s: end of replay", r->base.description);
        }
        if (st != MOCAP_OK) return st;
        r->pending = data;
        r->pending_len = len;
        r->pending_off = 0;
        r->pending_ns = ns;
        r->pending_due_ns = r->realtime ? due_time(r, ns) : 0;
    }

    if (r->realtime && r->pending_off == 0) {
        int64_t now = mocap_monotonic_ns();
        int64_t deadline = now + (int64_t)(timeout_ms > 0 ? timeout_ms : 0) * 1000000LL;
        while (now < r->pending_due_ns) {
            if (now >= deadline) return MOCAP_ERR_TIMEOUT; /* the record stays pending */
            int64_t until = r->pending_due_ns < deadline ? r->pending_due_ns : deadline;
            int64_t wait_ms = (until - now + 999999) / 1000000;
            mocap_sleep_ms((int)(wait_ms > 0 ? wait_ms : 1));
            now = mocap_monotonic_ns();
        }
    }

    size_t n = r->pending_len - r->pending_off;
    if (n > cap) n = cap;
    memcpy(buf, r->pending + r->pending_off, n);
    r->pending_off += n;
    *got = n;
    *receive_ns = r->pending_ns;
    if (r->pending_off == r->pending_len) r->pending = NULL;
    return MOCAP_OK;
}

static mocap_status replay_reopen(transport *t)
{
    return mocap_fail(MOCAP_ERR_END_OF_STREAM, "%s: a replay cannot be reopened",
                      t->description);
}

static void replay_close(transport *t)
{
    replay_transport *r = (replay_transport *)t;
    capture_reader_close(r->reader);
    free(r);
}

static void replay_damage(const transport *t, uint64_t *chunks_skipped, int32_t *tail_damaged)
{
    const replay_transport *r = (const replay_transport *)t;
    *chunks_skipped = capture_reader_skipped(r->reader);
    *tail_damaged = capture_reader_tail(r->reader) ? 1 : 0;
}

static const transport_ops replay_ops = {replay_read, replay_reopen, replay_close, replay_damage};

mocap_status transport_open_replay(const char *path, int realtime, double speed, transport **out)
{
    if (out) *out = NULL;
    if (!path || !out)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "transport_open_replay: NULL argument");
    if (realtime && !(speed > 0.0 && isfinite(speed)))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "capture file %s: replay speed must be positive (got %g)", path, speed);
    replay_transport *r = (replay_transport *)calloc(1, sizeof *r);
    if (!r) return mocap_fail(MOCAP_ERR_NO_MEMORY, "capture file %s: out of memory", path);
    mocap_status st = capture_reader_open(path, &r->reader);
    if (st != MOCAP_OK) {
        free(r);
        return st; /* the reader's message names the file and the cause */
    }
    r->base.ops = &replay_ops;
    snprintf(r->base.description, sizeof r->base.description, "capture file %s", path);
    r->realtime = realtime;
    r->speed = realtime ? speed : 1.0;
    *out = &r->base;
    return MOCAP_OK;
}
