/* OSC 1.0 encoder: messages and bundles written into a caller's fixed buffer, no allocation.
 *
 * Wire format (OpenSound Control 1.0): every item is padded with zero bytes to a multiple of 4;
 * integers, floats and time tags are big-endian.
 *   message = address string, type tag string (",sif..."), arguments
 *   string  = bytes + NUL, padded to 4        int32 (i) = 4 bytes      float32 (f) = IEEE 754, 4 bytes
 *   timetag (t) = 64-bit NTP time (seconds since 1900 << 32 | fraction); 1 = "immediately"
 *   bundle  = "#bundle\0", timetag, then elements each prefixed by its int32 byte size
 *
 * Use: osc_writer_init, then (optionally osc_bundle_begin) osc_message_begin(address, ",sfff"),
 * one osc_arg_* per type tag in order, osc_message_end, ... osc_bundle_end, osc_writer_finish.
 * Any misuse (overflow, an argument that does not match its tag, a tag left unwritten, an
 * unbalanced bundle) makes the writer fail: osc_writer_finish returns 0 and `error` says why.
 * Bundles nest up to OSC_MAX_DEPTH. One writer per thread. */
#ifndef MOCAP_OSC_ENCODER_H
#define MOCAP_OSC_ENCODER_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define OSC_MAX_DEPTH 4
#define OSC_TIMETAG_IMMEDIATELY ((uint64_t)1)

typedef struct osc_writer {
    uint8_t *buf;
    size_t cap;
    size_t len;
    const char *error;            /* NULL while fine; a constant description after a failure */
    size_t size_at[OSC_MAX_DEPTH + 1]; /* offsets of pending element size prefixes */
    int depth;                    /* open bundles */
    int sizes;                    /* pending size prefixes (bundles and a message inside one) */
    int in_message;
    const char *tags;             /* the open message's type tags, after ',' */
    int next_tag;
} osc_writer;

void osc_writer_init(osc_writer *w, void *buf, size_t cap);
/* Opens a bundle (nested inside the current one, if any). */
void osc_bundle_begin(osc_writer *w, uint64_t timetag);
void osc_bundle_end(osc_writer *w);
/* Opens a message; typetags starts with ',' and lists i, f, s, t. */
void osc_message_begin(osc_writer *w, const char *address, const char *typetags);
void osc_arg_int32(osc_writer *w, int32_t v);
void osc_arg_float(osc_writer *w, float v);
void osc_arg_string(osc_writer *w, const char *s);
void osc_arg_timetag(osc_writer *w, uint64_t t);
void osc_message_end(osc_writer *w);
/* Total length of a complete packet, or 0 when the writer failed or something is still open. */
size_t osc_writer_finish(osc_writer *w);

/* Seconds since the Unix epoch -> NTP time tag. */
uint64_t osc_timetag_from_unix(double seconds);

#ifdef __cplusplus
}
#endif
#endif
