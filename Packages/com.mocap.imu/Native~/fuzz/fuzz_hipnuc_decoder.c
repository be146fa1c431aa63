/* libFuzzer target for the HiPNUC decoder.
 *
 * Each input is used three ways:
 *  1. as a byte stream, fed once whole and once in pieces whose sizes come from the input itself;
 *     both decoders must report identical frames, counters and buffered bytes, and every input
 *     byte must be accounted for (delivered frame, skipped, or still buffered);
 *  2. as a payload handed straight to hipnuc_parse_payload (any length, beyond the frame limit);
 *  3. wrapped into a valid frame (bytes 1.. as the payload), which must decode to exactly one
 *     frame whose samples equal those of the direct parse.
 * Any violated invariant aborts, which libFuzzer reports as a crash. */
#include "hipnuc_decoder.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct trace {
    uint64_t frames;
    uint64_t samples;
    uint64_t frame_bytes;
    uint64_t hash;
} trace;

static uint64_t fnv1a(uint64_t h, const void *data, size_t n)
{
    const uint8_t *p = data;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 0x100000001B3ull;
    return h;
}

static void check(int ok)
{
    if (!ok) abort();
}

static void on_frame(void *user, const hipnuc_frame *f)
{
    trace *t = user;
    check(f->sample_count <= HIPNUC_MAX_NODES);
    check(f->payload_length >= 1 && f->payload_length <= HIPNUC_MAX_PAYLOAD);
    t->frames++;
    t->samples += f->sample_count;
    t->frame_bytes += HIPNUC_HEADER_SIZE + f->payload_length;
    t->hash = fnv1a(t->hash, &f->payload_length, sizeof f->payload_length);
    t->hash = fnv1a(t->hash, &f->first_tag, sizeof f->first_tag);
    t->hash = fnv1a(t->hash, &f->gateway_id, sizeof f->gateway_id);
    t->hash = fnv1a(t->hash, &f->sample_count, sizeof f->sample_count);
    t->hash = fnv1a(t->hash, f->samples, f->sample_count * sizeof f->samples[0]);
}

static void check_accounting(const hipnuc_decoder *d, const trace *t)
{
    const hipnuc_stats *s = &d->stats;
    check(d->length < sizeof d->buffer);
    check(s->frames_ok == t->frames);
    check(s->samples == t->samples);
    check(s->bytes_in == t->frame_bytes + s->bytes_skipped + d->length);
    /* Every rejected candidate discards exactly its first byte. */
    check(s->crc_failures + s->bad_lengths <= s->bytes_skipped);
}

/* Static: the decoders are a few KB each and libFuzzer runs one input at a time. */
static hipnuc_decoder whole, pieces, wrapped;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) return 0;
    const int layout = data[0] % 3;

    /* 1. Streaming, whole vs. pieces. */
    trace tw = {0, 0, 0, 0xCBF29CE484222325ull}, tp = tw;
    hipnuc_decoder_init(&whole, layout);
    hipnuc_decoder_init(&pieces, layout);
    hipnuc_decoder_feed(&whole, data, size, on_frame, &tw);
    size_t pos = 0;
    for (size_t k = 0; pos < size; k++) {
        uint8_t b = data[(k * 7) % size];
        /* Mostly small pieces (partial headers and payloads), sometimes several frames' worth,
         * sometimes an empty feed. */
        size_t n = (b & 0x80) ? (size_t)(b & 0x7F) * 41 : (size_t)(b & 0x1F);
        if (n > size - pos) n = size - pos;
        hipnuc_decoder_feed(&pieces, data + pos, n, on_frame, &tp);
        pos += n;
        if (k > size * 4) { /* many empty feeds in a row: finish in one piece */
            hipnuc_decoder_feed(&pieces, data + pos, size - pos, on_frame, &tp);
            pos = size;
        }
    }
    check_accounting(&whole, &tw);
    check_accounting(&pieces, &tp);
    check(whole.stats.bytes_in == size);
    check(memcmp(&whole.stats, &pieces.stats, sizeof whole.stats) == 0);
    check(tw.hash == tp.hash && tw.frame_bytes == tp.frame_bytes);
    check(whole.length == pieces.length);
    check(memcmp(whole.buffer, pieces.buffer, whole.length) == 0);
    /* What is still buffered is the tail of the input. */
    check(memcmp(whole.buffer, data + size - whole.length, whole.length) == 0);

    /* 2. Direct payload parse, any length. */
    static hipnuc_frame direct;
    hipnuc_stats ps;
    memset(&ps, 0, sizeof ps);
    int n = hipnuc_parse_payload(data + 1, size - 1, layout, &direct, &ps);
    check(n >= 0 && n <= HIPNUC_MAX_NODES && (uint32_t)n == direct.sample_count);
    check(ps.samples == (uint64_t)n);
    /* Parsing stops at the first problem; a gateway overflow may also be truncated. */
    check(ps.unknown_tags + ps.truncated_packets + ps.node_overflows <= 2);

    /* 3. The same payload as a valid frame, after some garbage. */
    static uint8_t frame[HIPNUC_HEADER_SIZE + HIPNUC_MAX_PAYLOAD];
    size_t payload_len = size - 1;
    if (payload_len >= 1 && payload_len <= HIPNUC_MAX_PAYLOAD) {
        size_t framed = hipnuc_encode_frame(data + 1, payload_len, frame, sizeof frame);
        check(framed == HIPNUC_HEADER_SIZE + payload_len);
        trace tr = {0, 0, 0, 0};
        hipnuc_decoder_init(&wrapped, layout);
        const uint8_t junk[3] = {0x00, HIPNUC_SYNC1, 0x7E};
        hipnuc_decoder_feed(&wrapped, junk, sizeof junk, on_frame, &tr);
        hipnuc_decoder_feed(&wrapped, frame, framed, on_frame, &tr);
        check_accounting(&wrapped, &tr);
        check(tr.frames == 1 && wrapped.length == 0);
        check(wrapped.stats.bytes_skipped == sizeof junk && wrapped.stats.crc_failures == 0);
        const hipnuc_frame *f = &wrapped.frame;
        check(f->sample_count == direct.sample_count && f->first_tag == direct.first_tag &&
              f->gateway_id == direct.gateway_id && f->payload_length == payload_len);
        check(memcmp(f->samples, direct.samples, f->sample_count * sizeof f->samples[0]) == 0);
        check(wrapped.stats.unknown_tags == ps.unknown_tags &&
              wrapped.stats.truncated_packets == ps.truncated_packets &&
              wrapped.stats.node_overflows == ps.node_overflows);
    }
    return 0;
}
