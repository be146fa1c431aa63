/* `mocapctl bench decode`: single-core throughput of the HiPNUC decoder on the packet the
 * 6-sensor wireless kit actually sends (0x62 with six 0x91 blocks, 470 bytes per frame). */
#include "bench.h"

#include "error.h"
#include "hipnuc_decoder.h"
#include "platform.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define BENCH_NODES 6
#define BENCH_FRAMES 8192 /* ~3.9 MB: larger than typical L2, so the input streams from memory */
#define BENCH_CHUNK 4096  /* what a serial read typically returns */

typedef struct bench_counts {
    uint64_t frames;
    uint64_t samples;
    uint64_t bad_frames; /* frames that did not decode to BENCH_NODES samples */
} bench_counts;

static void count_frame(void *user, const hipnuc_frame *frame)
{
    bench_counts *c = user;
    c->frames++;
    c->samples += frame->sample_count;
    if (frame->sample_count != BENCH_NODES || frame->first_tag != HIPNUC_TAG_GWSOL) c->bad_frames++;
}

/* Plausible, changing sensor values: a slow rotation about a tilted axis plus small noise, so
 * that no two frames are alike (a decoder must not benefit from repeated bytes). */
static void make_sample(uint32_t node, uint32_t frame, uint32_t *rng, hipnuc_sample *s)
{
    memset(s, 0, sizeof *s);
    s->node_id = node + 1;
    s->time_ms = frame * 10u;
    float angle = 0.01f * (float)frame + 0.7f * (float)node;
    float c = cosf(0.5f * angle), sn = sinf(0.5f * angle);
    s->quat[0] = c;
    s->quat[1] = 0.36f * sn;
    s->quat[2] = 0.48f * sn;
    s->quat[3] = 0.8f * sn;
    for (int i = 0; i < 3; i++) {
        *rng = *rng * 1664525u + 1013904223u;
        float noise = (float)(*rng >> 8) * (1.0f / 16777216.0f) - 0.5f;
        s->acc_g[i] = (i == 2 ? 1.0f : 0.0f) + 0.02f * noise;
        s->gyr_dps[i] = 30.0f * sinf(angle + (float)i) + noise;
        s->mag_ut[i] = 25.0f * cosf(angle - (float)i) + 0.3f * noise;
        s->euler_deg[i] = fmodf(57.29578f * angle * (float)(i + 1), 360.0f) - 180.0f;
    }
}

static mocap_status build_stream(uint8_t **out, size_t *size)
{
    const size_t payload_size = HIPNUC_GWSOL_HEADER_SIZE + BENCH_NODES * HIPNUC_IMUSOL_SIZE;
    const size_t frame_size = HIPNUC_HEADER_SIZE + payload_size;
    uint8_t *stream = malloc(frame_size * BENCH_FRAMES);
    if (!stream)
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "bench decode: cannot allocate %zu bytes",
                          frame_size * BENCH_FRAMES);
    uint32_t rng = 12345u;
    hipnuc_sample samples[BENCH_NODES];
    uint8_t *p = stream;
    for (uint32_t f = 0; f < BENCH_FRAMES; f++) {
        for (uint32_t n = 0; n < BENCH_NODES; n++) make_sample(n, f, &rng, &samples[n]);
        size_t payload = hipnuc_encode_gwsol((uint8_t)1, samples, BENCH_NODES,
                                             p + HIPNUC_HEADER_SIZE, payload_size);
        size_t framed = hipnuc_encode_frame(p + HIPNUC_HEADER_SIZE, payload, p, frame_size);
        if (payload != payload_size || framed != frame_size) {
            free(stream);
            return mocap_fail(MOCAP_ERR_STATE, "bench decode: encoder produced %zu/%zu bytes",
                              payload, framed);
        }
        p += frame_size;
    }
    *out = stream;
    *size = frame_size * BENCH_FRAMES;
    return MOCAP_OK;
}

int mocapctl_bench_decode(double seconds, double *mb_per_s)
{
    if (mb_per_s) *mb_per_s = 0.0;
    if (!(seconds > 0.0) || seconds > 3600.0) {
        mocap_status st = mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                                     "bench decode: --seconds must be in (0, 3600], got %g",
                                     seconds);
        fprintf(stderr, "%s\n", mocap_last_error());
        return st;
    }
    uint8_t *stream = NULL;
    size_t size = 0;
    mocap_status st = build_stream(&stream, &size);
    if (st != MOCAP_OK) {
        fprintf(stderr, "%s\n", mocap_last_error());
        return st;
    }

    /* The decoder holds a 2.4 KB buffer and a 2.7 KB frame: keep it off the stack. */
    hipnuc_decoder *decoder = malloc(sizeof *decoder);
    if (!decoder) {
        free(stream);
        st = mocap_fail(MOCAP_ERR_NO_MEMORY, "bench decode: cannot allocate the decoder");
        fprintf(stderr, "%s\n", mocap_last_error());
        return st;
    }
    hipnuc_decoder_init(decoder, HIPNUC_LAYOUT_AUTO);
    bench_counts counts = {0, 0, 0};
    uint64_t passes = 0;
    const int64_t start = mocap_monotonic_ns();
    const int64_t budget = (int64_t)(seconds * 1e9);
    int64_t elapsed = 0;
    do {
        for (size_t off = 0; off < size; off += BENCH_CHUNK) {
            size_t n = size - off < BENCH_CHUNK ? size - off : BENCH_CHUNK;
            hipnuc_decoder_feed(decoder, stream + off, n, count_frame, &counts);
        }
        passes++;
        elapsed = mocap_monotonic_ns() - start;
    } while (elapsed < budget);

    const uint64_t expected = passes * BENCH_FRAMES;
    const hipnuc_stats *stats = &decoder->stats;
    if (counts.frames != expected || counts.bad_frames != 0 ||
        counts.samples != expected * BENCH_NODES || stats->crc_failures != 0 ||
        stats->bytes_skipped != 0 || decoder->length != 0) {
        st = mocap_fail(MOCAP_ERR_STATE,
                        "bench decode: decoded %llu frames (%llu malformed, %llu samples, %llu CRC "
                        "failures, %llu bytes skipped), expected %llu frames",
                        (unsigned long long)counts.frames, (unsigned long long)counts.bad_frames,
                        (unsigned long long)counts.samples,
                        (unsigned long long)stats->crc_failures,
                        (unsigned long long)stats->bytes_skipped, (unsigned long long)expected);
        fprintf(stderr, "%s\n", mocap_last_error());
    } else {
        const double secs = (double)elapsed * 1e-9;
        const double mbps = (double)size * (double)passes / secs / 1e6;
        const double fps = (double)counts.frames / secs;
        printf("decode: %.0f MB/s (%.0f frames/s), %d-node 0x62 frames, one core\n", mbps, fps,
               BENCH_NODES);
        if (mb_per_s) *mb_per_s = mbps;
    }
    free(decoder);
    free(stream);
    return st;
}
