/* HiPNUC frame decoder and encoder.
 *
 * Stream model: every input byte ends up in exactly one of three places: a delivered frame,
 * stats.bytes_skipped, or the partial frame held in decoder->buffer. A rejected candidate (bad
 * sync, impossible length, CRC failure) only ever discards its first byte; scanning resumes at
 * the next byte, so a corrupted length field that "swallowed" the following frames cannot lose
 * them. The same scan routine runs over the caller's bytes in place (fast path, no copy) and over
 * the internal buffer, and the buffer is only topped up with the bytes the pending candidate
 * still needs: that makes the result independent of how the stream is chunked.
 *
 * Callbacks must not feed or reset the decoder that is calling them. */
#include "hipnuc_decoder.h"

#include "crc.h"

#include <string.h>

/* AUTO accepts the newer firmware's status/temperature/pressure layout only when those bytes
 * make physical sense; the node-id layout leaves reserved bytes there that are zero or junk
 * (the Hi229 manual's own sample decodes to -4e-25 Pa). */
#define AUTO_PRESSURE_MIN_PA 10000.0f
#define AUTO_PRESSURE_MAX_PA 120000.0f
#define AUTO_TEMPERATURE_MIN_C (-40)
#define AUTO_TEMPERATURE_MAX_C 100

/* Sizes (tag included) of the older firmware's single-item packets. */
#define LEGACY_ID_SIZE 2
#define LEGACY_I16X3_SIZE 7
#define LEGACY_QUAT_SIZE 17
#define LEGACY_PRESSURE_SIZE 5

#define IMUSOL_ALL_MOTION_FIELDS                                                              \
    (HIPNUC_FIELD_TIME | HIPNUC_FIELD_ACC | HIPNUC_FIELD_GYR | HIPNUC_FIELD_MAG |              \
     HIPNUC_FIELD_EULER | HIPNUC_FIELD_QUAT)

/* Little-endian accessors assembled from bytes: alignment-safe and endian-independent; compilers
 * turn them into single loads on little-endian targets. */
static uint16_t read_u16(const uint8_t *p) { return (uint16_t)(p[0] | (unsigned)p[1] << 8); }

static int16_t read_i16(const uint8_t *p)
{
    uint16_t u = read_u16(p);
    int16_t v;
    memcpy(&v, &u, sizeof v); /* avoids the implementation-defined unsigned->signed conversion */
    return v;
}

static uint32_t read_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float read_f32(const uint8_t *p)
{
    uint32_t u = read_u32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static void write_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void write_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static void write_f32(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    write_u32(p, u);
}

static void read_f32s(const uint8_t *p, float *out, int n)
{
    for (int i = 0; i < n; i++) out[i] = read_f32(p + 4 * i);
}

static void write_f32s(uint8_t *p, const float *in, int n)
{
    for (int i = 0; i < n; i++) write_f32(p + 4 * i, in[i]);
}

static int status_layout_plausible(const uint8_t *block)
{
    int temperature = (int8_t)block[3];
    float pressure = read_f32(block + 4);
    /* The comparisons are false for NaN, and +-Inf falls outside the window. */
    return temperature >= AUTO_TEMPERATURE_MIN_C && temperature <= AUTO_TEMPERATURE_MAX_C &&
           pressure >= AUTO_PRESSURE_MIN_PA && pressure <= AUTO_PRESSURE_MAX_PA;
}

/* One 76-byte 0x91 block (block[0] is the tag). */
static void decode_imusol(const uint8_t *block, int layout, uint8_t source_tag, hipnuc_sample *s)
{
    memset(s, 0, sizeof *s);
    s->source_tag = source_tag;
    if (layout != HIPNUC_LAYOUT_NODE_ID && layout != HIPNUC_LAYOUT_STATUS_WORD)
        layout = status_layout_plausible(block) ? HIPNUC_LAYOUT_STATUS_WORD : HIPNUC_LAYOUT_NODE_ID;
    if (layout == HIPNUC_LAYOUT_STATUS_WORD) {
        s->status = read_u16(block + 1);
        s->temperature_c = (int8_t)block[3];
        s->pressure_pa = read_f32(block + 4);
        s->fields = HIPNUC_FIELD_STATUS | HIPNUC_FIELD_PRESSURE;
    } else {
        s->node_id = block[1];
        s->fields = HIPNUC_FIELD_NODE_ID;
    }
    s->fields |= IMUSOL_ALL_MOTION_FIELDS;
    s->time_ms = read_u32(block + 8);
    read_f32s(block + 12, s->acc_g, 3);
    read_f32s(block + 24, s->gyr_dps, 3);
    read_f32s(block + 36, s->mag_ut, 3);
    read_f32s(block + 48, s->euler_deg, 3);
    read_f32s(block + 60, s->quat, 4);
}

static size_t legacy_item_size(uint8_t tag)
{
    switch (tag) {
    case HIPNUC_TAG_ID: return LEGACY_ID_SIZE;
    case HIPNUC_TAG_ACC:
    case HIPNUC_TAG_GYR:
    case HIPNUC_TAG_MAG:
    case HIPNUC_TAG_EULER: return LEGACY_I16X3_SIZE;
    case HIPNUC_TAG_QUAT: return LEGACY_QUAT_SIZE;
    case HIPNUC_TAG_PRESSURE: return LEGACY_PRESSURE_SIZE;
    default: return 0;
    }
}

static void decode_legacy_item(const uint8_t *item, hipnuc_sample *s)
{
    const uint8_t *v = item + 1;
    switch (item[0]) {
    case HIPNUC_TAG_ID:
        s->node_id = v[0];
        s->fields |= HIPNUC_FIELD_NODE_ID;
        break;
    case HIPNUC_TAG_ACC: /* 0.001 g */
        for (int i = 0; i < 3; i++) s->acc_g[i] = (float)read_i16(v + 2 * i) * 0.001f;
        s->fields |= HIPNUC_FIELD_ACC;
        break;
    case HIPNUC_TAG_GYR: /* 0.1 deg/s */
        for (int i = 0; i < 3; i++) s->gyr_dps[i] = (float)read_i16(v + 2 * i) * 0.1f;
        s->fields |= HIPNUC_FIELD_GYR;
        break;
    case HIPNUC_TAG_MAG: /* 0.001 Gauss = 0.1 uT */
        for (int i = 0; i < 3; i++) s->mag_ut[i] = (float)read_i16(v + 2 * i) * 0.1f;
        s->fields |= HIPNUC_FIELD_MAG;
        break;
    case HIPNUC_TAG_EULER: /* wire order pitch/100, roll/100, yaw/10; stored roll, pitch, yaw */
        s->euler_deg[0] = (float)read_i16(v + 2) * 0.01f;
        s->euler_deg[1] = (float)read_i16(v) * 0.01f;
        s->euler_deg[2] = (float)read_i16(v + 4) * 0.1f;
        s->fields |= HIPNUC_FIELD_EULER;
        break;
    case HIPNUC_TAG_QUAT:
        read_f32s(v, s->quat, 4);
        s->fields |= HIPNUC_FIELD_QUAT;
        break;
    case HIPNUC_TAG_PRESSURE:
        s->pressure_pa = read_f32(v);
        s->fields |= HIPNUC_FIELD_PRESSURE;
        break;
    default: break;
    }
}

int hipnuc_parse_payload(const uint8_t *payload, size_t len, int layout, hipnuc_frame *out,
                         hipnuc_stats *stats)
{
    hipnuc_stats scratch;
    if (!stats) {
        memset(&scratch, 0, sizeof scratch);
        stats = &scratch;
    }
    if (!out) return 0;
    out->payload_length = (uint16_t)(len > 0xFFFFu ? 0xFFFFu : len);
    out->first_tag = (len > 0 && payload) ? payload[0] : 0;
    out->gateway_id = 0;
    out->sample_count = 0;
    if (!payload) return 0;

    hipnuc_sample *chain = NULL; /* older firmware: all chained items describe one sample */
    size_t pos = 0;
    while (pos < len) {
        const uint8_t *p = payload + pos;
        size_t left = len - pos;
        uint8_t tag = p[0];

        if (tag == HIPNUC_TAG_IMUSOL) {
            if (left < HIPNUC_IMUSOL_SIZE) {
                stats->truncated_packets++;
                break;
            }
            if (out->sample_count >= HIPNUC_MAX_NODES) {
                stats->node_overflows++;
                break;
            }
            decode_imusol(p, layout, HIPNUC_TAG_IMUSOL, &out->samples[out->sample_count++]);
            pos += HIPNUC_IMUSOL_SIZE;
            continue;
        }

        if (tag == HIPNUC_TAG_GWSOL) {
            if (left < HIPNUC_GWSOL_HEADER_SIZE) {
                stats->truncated_packets++;
                break;
            }
            uint32_t claimed = p[2];
            uint32_t room = HIPNUC_MAX_NODES - out->sample_count;
            uint32_t take = claimed < room ? claimed : room;
            /* An overflowing count leaves us unable to find what follows, so it ends the walk
             * after the blocks we can hold. */
            if (claimed > take) stats->node_overflows++;
            if (left < HIPNUC_GWSOL_HEADER_SIZE + (size_t)take * HIPNUC_IMUSOL_SIZE) {
                stats->truncated_packets++;
                break;
            }
            out->gateway_id = p[1];
            const uint8_t *block = p + HIPNUC_GWSOL_HEADER_SIZE;
            for (uint32_t i = 0; i < take; i++, block += HIPNUC_IMUSOL_SIZE) {
                if (block[0] != HIPNUC_TAG_IMUSOL) {
                    stats->unknown_tags++;
                    goto done;
                }
                /* Gateway blocks always carry the node id in byte 1, whatever the firmware. */
                decode_imusol(block, HIPNUC_LAYOUT_NODE_ID, HIPNUC_TAG_GWSOL,
                              &out->samples[out->sample_count++]);
            }
            if (claimed > take) break;
            pos += HIPNUC_GWSOL_HEADER_SIZE + (size_t)claimed * HIPNUC_IMUSOL_SIZE;
            continue;
        }

        size_t size = legacy_item_size(tag);
        if (size == 0) {
            stats->unknown_tags++;
            break;
        }
        if (left < size) {
            stats->truncated_packets++;
            break;
        }
        if (!chain) {
            if (out->sample_count >= HIPNUC_MAX_NODES) {
                stats->node_overflows++;
                break;
            }
            chain = &out->samples[out->sample_count++];
            memset(chain, 0, sizeof *chain);
            chain->source_tag = tag;
        }
        decode_legacy_item(p, chain);
        pos += size;
    }
done:
    stats->samples += out->sample_count;
    return (int)out->sample_count;
}

void hipnuc_decoder_init(hipnuc_decoder *decoder, int layout)
{
    if (!decoder) return;
    memset(decoder, 0, sizeof *decoder);
    decoder->layout = layout;
}

void hipnuc_decoder_reset(hipnuc_decoder *decoder)
{
    if (decoder) decoder->length = 0;
}

/* Decode every frame in p[0..n) and return how many bytes were consumed; the rest (always
 * shorter than a maximal frame) is the start of a candidate frame that needs more bytes. */
static size_t scan_frames(hipnuc_decoder *d, const uint8_t *p, size_t n, hipnuc_frame_fn on_frame,
                          void *user)
{
    size_t i = 0;
    while (i < n) {
        if (p[i] != HIPNUC_SYNC0) {
            const uint8_t *q = memchr(p + i, HIPNUC_SYNC0, n - i);
            size_t next = q ? (size_t)(q - p) : n;
            d->stats.bytes_skipped += next - i;
            i = next;
            if (!q) break;
        }
        size_t left = n - i;
        if (left < 2) break;
        if (p[i + 1] != HIPNUC_SYNC1) {
            d->stats.bytes_skipped++;
            i++;
            continue;
        }
        if (left < 4) break;
        size_t payload_len = read_u16(p + i + 2);
        if (payload_len == 0 || payload_len > HIPNUC_MAX_PAYLOAD) {
            d->stats.bad_lengths++;
            d->stats.bytes_skipped++;
            i++;
            continue;
        }
        if (left < HIPNUC_HEADER_SIZE + payload_len) break;
        const uint8_t *payload = p + i + HIPNUC_HEADER_SIZE;
        uint16_t crc = crc16_xmodem_update(0, p + i, 4);
        crc = crc16_xmodem_update(crc, payload, payload_len);
        if (crc != read_u16(p + i + 4)) {
            d->stats.crc_failures++;
            d->stats.bytes_skipped++;
            i++;
            continue;
        }
        d->stats.frames_ok++;
        hipnuc_parse_payload(payload, payload_len, d->layout, &d->frame, &d->stats);
        if (on_frame) on_frame(user, &d->frame);
        i += HIPNUC_HEADER_SIZE + payload_len;
    }
    return i;
}

void hipnuc_decoder_feed(hipnuc_decoder *decoder, const uint8_t *data, size_t len,
                         hipnuc_frame_fn on_frame, void *user)
{
    if (!decoder || !data) return;
    decoder->stats.bytes_in += len;
    while (len > 0) {
        if (decoder->length == 0) {
            /* Fast path: whole frames are decoded straight from the caller's bytes. */
            size_t used = scan_frames(decoder, data, len, on_frame, user);
            memcpy(decoder->buffer, data + used, len - used);
            decoder->length = len - used;
            return;
        }
        /* Complete the pending candidate with exactly the bytes it still needs (first the
         * header, then the payload its validated length field announces). */
        size_t want = HIPNUC_HEADER_SIZE;
        if (decoder->length >= 4) want += read_u16(decoder->buffer + 2);
        size_t take = want - decoder->length;
        if (take > len) take = len;
        memcpy(decoder->buffer + decoder->length, data, take);
        decoder->length += take;
        data += take;
        len -= take;
        size_t used = scan_frames(decoder, decoder->buffer, decoder->length, on_frame, user);
        memmove(decoder->buffer, decoder->buffer + used, decoder->length - used);
        decoder->length -= used;
    }
}

void hipnuc_decoder_flush(hipnuc_decoder *decoder, hipnuc_frame_fn on_frame, void *user)
{
    if (!decoder) return;
    /* Each round drops the first byte of the candidate that cannot complete, so this ends. */
    while (decoder->length > 0) {
        decoder->stats.bytes_skipped++;
        decoder->length--;
        memmove(decoder->buffer, decoder->buffer + 1, decoder->length);
        size_t used = scan_frames(decoder, decoder->buffer, decoder->length, on_frame, user);
        memmove(decoder->buffer, decoder->buffer + used, decoder->length - used);
        decoder->length -= used;
    }
}

size_t hipnuc_encode_frame(const uint8_t *payload, size_t len, uint8_t *out, size_t cap)
{
    if (!out || len > HIPNUC_MAX_PAYLOAD || (len > 0 && !payload) ||
        cap < HIPNUC_HEADER_SIZE + len)
        return 0;
    /* memmove: callers may build the payload in place at out + HIPNUC_HEADER_SIZE. */
    if (len > 0) memmove(out + HIPNUC_HEADER_SIZE, payload, len);
    out[0] = HIPNUC_SYNC0;
    out[1] = HIPNUC_SYNC1;
    write_u16(out + 2, (uint16_t)len);
    uint16_t crc = crc16_xmodem_update(0, out, 4);
    crc = crc16_xmodem_update(crc, out + HIPNUC_HEADER_SIZE, len);
    write_u16(out + 4, crc);
    return HIPNUC_HEADER_SIZE + len;
}

void hipnuc_encode_imusol(const hipnuc_sample *s, int layout, uint8_t out[HIPNUC_IMUSOL_SIZE])
{
    memset(out, 0, HIPNUC_IMUSOL_SIZE);
    out[0] = HIPNUC_TAG_IMUSOL;
    if (layout == HIPNUC_LAYOUT_STATUS_WORD) {
        write_u16(out + 1, s->status);
        out[3] = (uint8_t)s->temperature_c;
        write_f32(out + 4, s->pressure_pa);
    } else {
        out[1] = (uint8_t)s->node_id;
    }
    write_u32(out + 8, s->time_ms);
    write_f32s(out + 12, s->acc_g, 3);
    write_f32s(out + 24, s->gyr_dps, 3);
    write_f32s(out + 36, s->mag_ut, 3);
    write_f32s(out + 48, s->euler_deg, 3);
    write_f32s(out + 60, s->quat, 4);
}

size_t hipnuc_encode_gwsol(uint8_t gateway_id, const hipnuc_sample *samples, uint32_t n,
                           uint8_t *out, size_t cap)
{
    /* The count is one byte on the wire. n may exceed HIPNUC_MAX_NODES so that tests can build
     * overflowing packets; such a payload is only framable while it fits HIPNUC_MAX_PAYLOAD. */
    if (!out || n > 0xFFu || (n > 0 && !samples)) return 0;
    size_t size = HIPNUC_GWSOL_HEADER_SIZE + (size_t)n * HIPNUC_IMUSOL_SIZE;
    if (cap < size) return 0;
    memset(out, 0, HIPNUC_GWSOL_HEADER_SIZE);
    out[0] = HIPNUC_TAG_GWSOL;
    out[1] = gateway_id;
    out[2] = (uint8_t)n;
    for (uint32_t i = 0; i < n; i++)
        hipnuc_encode_imusol(&samples[i], HIPNUC_LAYOUT_NODE_ID,
                             out + HIPNUC_GWSOL_HEADER_SIZE + (size_t)i * HIPNUC_IMUSOL_SIZE);
    return size;
}
