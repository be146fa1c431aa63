/* Frame assembly: resamples each sensor's irregular sample stream onto one fixed output grid.
 *
 * The grid is the set of integer multiples of the period (origin 0 on the session clock), so two
 * runs over the same data produce the same frame times, and every frame time is computed as
 * index * period instead of by repeated addition (no drift over long sessions). */
#include "frame_assembler.h"

#include <math.h>
#include <string.h>

#include "mocap_math.h"

/* Timestamps are millisecond counters mapped through double arithmetic; two times closer than
 * this are the same instant, so a sample that lands on a grid point counts as bracketing it. */
#define ASM_TIME_EPS 1e-9

/* What one sensor contributes to the frame at time t. */
typedef struct track_view {
    const imu_sample *before; /* newest sample at or before t, or NULL */
    const imu_sample *after;  /* oldest sample at or after t, or NULL */
} track_view;

static const imu_sample *track_at(const sensor_track *k, uint32_t i)
{
    return &k->samples[(k->head + i) % ASSEMBLER_HISTORY];
}

static const imu_sample *track_newest(const sensor_track *k)
{
    return k->count ? track_at(k, k->count - 1) : NULL;
}

/* The history is strictly increasing in time (older or equal samples are dropped at push), so
 * one backwards scan finds both neighbours of t. */
static track_view track_find(const sensor_track *k, double t)
{
    track_view v = {NULL, NULL};
    uint32_t i = k->count;
    while (i > 0) {
        const imu_sample *s = track_at(k, i - 1);
        if (s->t >= t - ASM_TIME_EPS)
            v.after = s;
        if (s->t <= t + ASM_TIME_EPS) {
            v.before = s;
            break;
        }
        i--;
    }
    return v;
}

static int64_t grid_index_at_or_after(double period, double t)
{
    return (int64_t)ceil((t - ASM_TIME_EPS) / period);
}

/* next_t always holds index * period exactly as computed here, so its index is recovered by
 * rounding and the struct needs no separate counter. */
static double grid_time(double period, int64_t index)
{
    return (double)index * period;
}

static int64_t grid_index_of(double period, double t)
{
    return (int64_t)llround(t / period);
}

void assembler_init(frame_assembler *a, double rate_hz, double hold_latency_s, double stale_after_s)
{
    memset(a, 0, sizeof(*a));
    /* Config is validated upstream; still keep the grid well defined if a caller slips. */
    a->period = (rate_hz > 0.0 && isfinite(rate_hz)) ? 1.0 / rate_hz : 1.0 / 60.0;
    a->hold_latency = hold_latency_s > 0.0 ? hold_latency_s : 0.0;
    a->stale_after = stale_after_s > 0.0 ? stale_after_s : 0.0;
}

int assembler_is_newer(const frame_assembler *a, int segment, double t)
{
    if (segment < 0 || segment >= MOCAP_MAX_SENSORS || !isfinite(t)) return 0;
    const sensor_track *k = &a->tracks[segment];
    const imu_sample *newest = track_newest(k);
    return !newest || t > newest->t;
}

void assembler_push(frame_assembler *a, const imu_sample *s)
{
    if (s->segment < 0 || s->segment >= MOCAP_MAX_SENSORS || !isfinite(s->t))
        return;
    sensor_track *k = &a->tracks[s->segment];
    const imu_sample *newest = track_newest(k);
    if (newest && s->t <= newest->t) {
        a->out_of_order++;
        return;
    }
    if (k->count < ASSEMBLER_HISTORY) {
        k->samples[(k->head + k->count) % ASSEMBLER_HISTORY] = *s;
        k->count++;
    } else {
        /* Overwrite the oldest: frames lag the newest data by about hold_latency, far less than
         * the history span, and a frame whose samples are gone falls back to the oldest left. */
        k->samples[k->head] = *s;
        k->head = (k->head + 1) % ASSEMBLER_HISTORY;
    }
    k->seen = 1;
    if (!a->started) {
        a->started = 1;
        a->next_t = grid_time(a->period, grid_index_at_or_after(a->period, s->t));
        a->resume_t = a->next_t;
    }
}

/* A sensor is stale at t when its newest sample at or before t is older than stale_after. A
 * sensor with only later samples (start-up, or history overrun) is not: it has current data. */
static int track_stale_at(const frame_assembler *a, const track_view *v, double t)
{
    return v->before && (t - v->before->t) > a->stale_after;
}

static void fill_sensor(const frame_assembler *a, int s, const track_view *v, double t,
                        raw_frame *out)
{
    const imu_sample *src;
    const uint32_t bit = 1u << s;
    out->valid_mask |= bit;
    out->age[s] = v->before ? fmax(0.0, t - v->before->t) : 0.0;
    if (track_stale_at(a, v, t))
        out->stale_mask |= bit;

    if (v->before && v->after) {
        const double span = v->after->t - v->before->t;
        if (span <= ASM_TIME_EPS) {
            src = v->before; /* a sample on the grid point: it is the value */
            out->fresh_mask |= bit;
        } else if (span <= a->stale_after) {
            const double u = (t - v->before->t) / span;
            const double w = u < 0.0 ? 0.0 : (u > 1.0 ? 1.0 : u);
            quat_slerp(out->quat[s], v->before->quat, v->after->quat, w);
            for (int i = 0; i < 3; i++) {
                out->force_world[s][i] =
                    v->before->force_world[i] + w * (v->after->force_world[i] - v->before->force_world[i]);
                out->gyr[s][i] = v->before->gyr[i] + w * (v->after->gyr[i] - v->before->gyr[i]);
            }
            out->node_id[s] = v->before->node_id;
            out->fresh_mask |= bit;
            return;
        } else {
            /* Samples on both sides of a dropout: interpolating across it would invent motion
             * the sensor never reported, so the frame holds what was known at t. */
            src = v->before;
        }
    } else {
        src = v->before ? v->before : v->after;
    }
    memcpy(out->quat[s], src->quat, sizeof(out->quat[s]));
    memcpy(out->force_world[s], src->force_world, sizeof(out->force_world[s]));
    memcpy(out->gyr[s], src->gyr, sizeof(out->gyr[s]));
    out->node_id[s] = src->node_id;
}

static void emit(frame_assembler *a, const track_view *views, double t, raw_frame *out)
{
    memset(out, 0, sizeof(*out));
    out->sequence = a->sequence++;
    out->t = t;
    for (int s = 0; s < MOCAP_MAX_SENSORS; s++) {
        quat_identity(out->quat[s]);
        if (a->tracks[s].seen && a->tracks[s].count)
            fill_sensor(a, s, &views[s], t, out);
    }
    a->next_t = grid_time(a->period, grid_index_of(a->period, t) + 1);
}

int assembler_next(frame_assembler *a, double now_s, raw_frame *out)
{
    if (!a->started)
        return 0;
    for (;;) {
        const double t = a->next_t;
        track_view views[MOCAP_MAX_SENSORS];
        int any_valid = 0, any_live = 0, all_arrived = 1;
        double first_new = INFINITY; /* earliest sample after t over all sensors */

        for (int s = 0; s < MOCAP_MAX_SENSORS; s++) {
            const sensor_track *k = &a->tracks[s];
            views[s].before = views[s].after = NULL;
            if (!k->seen || !k->count)
                continue;
            any_valid = 1;
            views[s] = track_find(k, t);
            const int stale = track_stale_at(a, &views[s], t);
            if (!stale)
                any_live = 1;
            /* After a (re)start sensors resume one by one, and a frame should not go out with
             * only the first, so stale sensors are waited for (up to hold_latency) then; later a
             * stale sensor is gone and waiting for it would only add latency to every frame. */
            if (!views[s].after && (!stale || t < a->resume_t + a->stale_after))
                all_arrived = 0;
            if (views[s].after && views[s].after->t < first_new)
                first_new = views[s].after->t;
        }
        if (!any_valid)
            return 0;

        if (!any_live) {
            /* Everything is old at t: no frame of pure held data. Restart the grid at the first
             * sample that came after the silence, or wait for one. Only next_t moves, so
             * sequence numbers stay consecutive across the gap. */
            if (!isfinite(first_new))
                return 0;
            int64_t index = grid_index_at_or_after(a->period, first_new);
            if (index <= grid_index_of(a->period, t))
                index = grid_index_of(a->period, t) + 1; /* always make progress */
            a->next_t = grid_time(a->period, index);
            a->resume_t = a->next_t;
            continue;
        }
        if (all_arrived || now_s >= t + a->hold_latency) {
            emit(a, views, t, out);
            return 1;
        }
        return 0;
    }
}
