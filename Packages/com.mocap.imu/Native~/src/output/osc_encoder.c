/* OSC 1.0 encoder (see osc_encoder.h).
 *
 * Why our own encoder and not liblo: the engine ships as one native plugin inside Unity on
 * Windows, macOS and Linux with no other native dependency. liblo would be a second library to
 * build and ship per platform (and it is LGPL, so it would have to stay a separately replaceable
 * shared library next to ours), it allocates per message (lo_message_new / lo_bundle_new), and
 * it brings its own socket layer and server threads we do not need: the VMC sender only writes
 * a handful of message shapes (,i ,iii ,f ,sfffffff) into one bundle per frame. What we use of
 * OSC is small and fully specified (4-byte padding, big-endian int32/float32/timetag, size-
 * prefixed bundle elements), so it is encoded here into a fixed buffer, byte-exact tests in
 * tests/test_osc_encoder.cpp check it against hand-computed bytes, and a real OSC implementation
 * (liblo's oscdump, tests/test_vmc_oscdump.cpp) decodes what we send. */
#include "osc_encoder.h"

#include <math.h>
#include <string.h>

static void fail(osc_writer *w, const char *why)
{
    if (!w->error) w->error = why;
}

static int room(osc_writer *w, size_t n)
{
    if (w->error) return 0;
    if (n > w->cap - w->len) {
        fail(w, "buffer too small");
        return 0;
    }
    return 1;
}

static void put_u32(osc_writer *w, uint32_t v)
{
    if (!room(w, 4)) return;
    uint8_t *p = w->buf + w->len;
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
    w->len += 4;
}

static void patch_u32(osc_writer *w, size_t at, uint32_t v)
{
    uint8_t *p = w->buf + at;
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

/* The string, its NUL and zero padding to a multiple of 4. */
static void put_string(osc_writer *w, const char *s)
{
    size_t n = strlen(s);
    size_t padded = (n + 4) & ~(size_t)3;
    if (!room(w, padded)) return;
    memcpy(w->buf + w->len, s, n);
    memset(w->buf + w->len + n, 0, padded - n);
    w->len += padded;
}

/* Element size prefix when inside a bundle: reserved now, written when the element ends. */
static void open_sized(osc_writer *w)
{
    if (w->depth == 0) return;
    if (w->sizes >= OSC_MAX_DEPTH + 1) {
        fail(w, "bundles nested too deep");
        return;
    }
    size_t at = w->len;
    put_u32(w, 0);
    if (w->error) return;
    w->size_at[w->sizes++] = at;
}

static void close_sized(osc_writer *w)
{
    if (w->error || w->sizes == 0) return;
    size_t at = w->size_at[--w->sizes];
    patch_u32(w, at, (uint32_t)(w->len - at - 4));
}

void osc_writer_init(osc_writer *w, void *buf, size_t cap)
{
    memset(w, 0, sizeof *w);
    w->buf = (uint8_t *)buf;
    w->cap = buf ? cap : 0;
}

void osc_bundle_begin(osc_writer *w, uint64_t timetag)
{
    if (w->in_message) fail(w, "bundle inside a message");
    if (w->error) return;
    if (w->depth >= OSC_MAX_DEPTH) {
        fail(w, "bundles nested too deep");
        return;
    }
    if (w->depth == 0 && w->len != 0) {
        fail(w, "a packet holds one message or one bundle");
        return;
    }
    open_sized(w);
    put_string(w, "#bundle");
    put_u32(w, (uint32_t)(timetag >> 32));
    put_u32(w, (uint32_t)timetag);
    if (!w->error) w->depth++;
}

void osc_bundle_end(osc_writer *w)
{
    if (w->in_message) fail(w, "bundle ended inside a message");
    if (w->depth == 0) fail(w, "no bundle is open");
    if (w->error) return;
    w->depth--;
    if (w->depth > 0) close_sized(w);
}

void osc_message_begin(osc_writer *w, const char *address, const char *typetags)
{
    if (w->in_message) fail(w, "message inside a message");
    if (!address || address[0] != '/') fail(w, "an OSC address starts with '/'");
    if (!typetags || typetags[0] != ',') fail(w, "type tags start with ','");
    if (w->depth == 0 && w->len != 0) fail(w, "a packet holds one message or one bundle");
    if (w->error) return;
    for (const char *t = typetags + 1; *t; ++t) {
        if (*t != 'i' && *t != 'f' && *t != 's' && *t != 't') {
            fail(w, "unsupported type tag");
            return;
        }
    }
    open_sized(w);
    put_string(w, address);
    put_string(w, typetags);
    w->tags = typetags + 1;
    w->next_tag = 0;
    w->in_message = 1;
}

/* Checks that the next argument of the open message has type tag `tag`. */
static int expect(osc_writer *w, char tag)
{
    if (w->error) return 0;
    if (!w->in_message) {
        fail(w, "argument outside a message");
        return 0;
    }
    if (w->tags[w->next_tag] != tag) {
        fail(w, w->tags[w->next_tag] ? "argument does not match its type tag"
                                     : "more arguments than type tags");
        return 0;
    }
    w->next_tag++;
    return 1;
}

void osc_arg_int32(osc_writer *w, int32_t v)
{
    if (expect(w, 'i')) put_u32(w, (uint32_t)v);
}

void osc_arg_float(osc_writer *w, float v)
{
    uint32_t bits;
    memcpy(&bits, &v, 4); /* IEEE 754 binary32 on every platform we build for */
    if (expect(w, 'f')) put_u32(w, bits);
}

void osc_arg_string(osc_writer *w, const char *s)
{
    if (expect(w, 's')) put_string(w, s ? s : "");
}

void osc_arg_timetag(osc_writer *w, uint64_t t)
{
    if (!expect(w, 't')) return;
    put_u32(w, (uint32_t)(t >> 32));
    put_u32(w, (uint32_t)t);
}

void osc_message_end(osc_writer *w)
{
    if (!w->in_message) fail(w, "no message is open");
    else if (w->tags[w->next_tag] != '\0') fail(w, "fewer arguments than type tags");
    if (w->error) return;
    w->in_message = 0;
    close_sized(w);
}

size_t osc_writer_finish(osc_writer *w)
{
    if (w->in_message) fail(w, "a message is still open");
    if (w->depth != 0) fail(w, "a bundle is still open");
    if (w->len == 0) fail(w, "empty packet");
    return w->error ? 0 : w->len;
}

uint64_t osc_timetag_from_unix(double seconds)
{
    /* NTP era 0 starts 1900-01-01; the Unix epoch is 2208988800 s later. */
    if (!(seconds >= 0) || !isfinite(seconds)) return OSC_TIMETAG_IMMEDIATELY;
    /* The 32-bit seconds field wraps every 2^32 s (NTP eras; era 1 starts in 2036). Wrapping
     * here keeps the conversion to integers defined for any time. */
    double ntp = fmod(seconds + 2208988800.0, 4294967296.0);
    uint64_t whole = (uint64_t)ntp;
    double frac = ntp - (double)whole;
    uint64_t f = (uint64_t)(frac * 4294967296.0);
    if (f > 0xffffffffu) f = 0xffffffffu;
    return (whole << 32) | f;
}
