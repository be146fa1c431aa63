/* Raw capture files (docs/capture-format.md). The writer fills one preallocated chunk buffer and
 * hands each chunk to the OS with a single write(), so a process killed at any instant leaves
 * at most one partial chunk at the end of the file; the reader skips damaged chunks by scanning
 * for the next chunk magic and proving the candidate with its CRC. */
#if !defined(_WIN32)
#define _FILE_OFFSET_BITS 64 /* captures may pass 2 GiB on 32-bit hosts */
#define _POSIX_C_SOURCE 200809L
#endif

#include "capture_file.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "crc.h"
#include "error.h"
#include "platform.h"

#if defined(_WIN32)
#define WIN32_LEAN_AND_MEAN
#include <fcntl.h>
#include <io.h>
#include <sys/stat.h>
#include <windows.h>
#else
#include <fcntl.h>
#include <sys/types.h>
#include <unistd.h>
#endif

/* ---------------------------------------------------------------------------------------- */
/* Layout constants: any change here is a format change (bump CAPTURE_FORMAT_VERSION).        */

#define CAPTURE_FORMAT_VERSION 1u
static const uint8_t FILE_MAGIC[8] = {'M', 'O', 'C', 'A', 'P', 'R', 'A', 'W'};
static const uint8_t CHUNK_MAGIC[4] = {'M', 'C', 'H', 'K'};

#define FILE_HEADER_FIXED 12     /* magic, version, header size: stable in every version */
#define FILE_HEADER_V1_SIZE 284  /* ... + flags, created, source, CRC */
#define FILE_HEADER_MAX 65535u   /* the header size field is a u16 */
#define SOURCE_OFFSET 24
#define SOURCE_FIELD 256
#define CHUNK_HEADER_SIZE 36
#define CHUNK_CRC_OFFSET 32
#define RECORD_HEADER_SIZE 10    /* i64 receive_ns + u16 length */
#define CHUNK_BUFFER_SIZE (CHUNK_HEADER_SIZE + CAPTURE_CHUNK_CAPACITY)

static void put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static void put_u32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i));
}
static void put_i64(uint8_t *p, int64_t v)
{
    uint64_t u = (uint64_t)v;
    for (int i = 0; i < 8; i++) p[i] = (uint8_t)(u >> (8 * i));
}
static uint16_t get_u16(const uint8_t *p) { return (uint16_t)(p[0] | (uint16_t)p[1] << 8); }
static uint32_t get_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static int64_t get_i64(const uint8_t *p)
{
    uint64_t u = 0;
    for (int i = 7; i >= 0; i--) u = u << 8 | p[i];
    return (int64_t)u;
}

/* ---------------------------------------------------------------------------------------- */
/* Thin file layer: raw descriptors, because stdio would split or merge our writes.          */

static int file_open(const char *path, int writing)
{
    /* UTF-8 path; not inherited by started programs; binary on Windows. */
    return mocap_open_descriptor(path, writing);
}

static int file_close(int fd)
{
#if defined(_WIN32)
    return _close(fd);
#else
    return close(fd);
#endif
}

/* Write everything; returns 0 or an errno value. Normally one call: the loop only continues
 * after a signal or a short write (which a full disk reports before failing outright). */
static int file_write_all(int fd, const uint8_t *data, size_t len)
{
    while (len > 0) {
#if defined(_WIN32)
        int n = _write(fd, data, (unsigned)len);
#else
        ssize_t n = write(fd, data, len);
#endif
        if (n < 0) {
            if (errno == EINTR) continue;
            return errno ? errno : EIO;
        }
        if (n == 0) return ENOSPC; /* no progress and no error: treat as out of space */
        data += n;
        len -= (size_t)n;
    }
    return 0;
}

/* Read up to len bytes at offset; *got < len only at end of file. Returns 0 or an errno. */
static int file_read_at(int fd, int64_t offset, uint8_t *buf, size_t len, size_t *got)
{
    *got = 0;
#if defined(_WIN32)
    if (_lseeki64(fd, offset, SEEK_SET) < 0) return errno;
#else
    if (lseek(fd, (off_t)offset, SEEK_SET) == (off_t)-1) return errno;
#endif
    while (*got < len) {
#if defined(_WIN32)
        int n = _read(fd, buf + *got, (unsigned)(len - *got));
#else
        ssize_t n = read(fd, buf + *got, len - *got);
#endif
        if (n < 0) {
            if (errno == EINTR) continue;
            return errno ? errno : EIO;
        }
        if (n == 0) break;
        *got += (size_t)n;
    }
    return 0;
}

static mocap_status open_failure(const char *path, const char *what, int err)
{
    char text[128];
    mocap_errno_text(err, text, sizeof text);
    mocap_status st = MOCAP_ERR_IO;
    if (err == ENOENT || err == ENOTDIR) st = MOCAP_ERR_NOT_FOUND;
    else if (err == EACCES || err == EPERM) st = MOCAP_ERR_PERMISSION;
    return mocap_fail(st, "capture file %s: %s: %s", path, what, text);
}

static int64_t wall_clock_unix_ns(void)
{
#if defined(_WIN32)
    FILETIME ft; /* 100 ns ticks since 1601-01-01 */
    GetSystemTimeAsFileTime(&ft);
    uint64_t ticks = (uint64_t)ft.dwHighDateTime << 32 | ft.dwLowDateTime;
    return (int64_t)(ticks - 116444736000000000ULL) * 100;
#else
    struct timespec ts;
    if (clock_gettime(CLOCK_REALTIME, &ts) != 0) return 0;
    return (int64_t)ts.tv_sec * 1000000000LL + (int64_t)ts.tv_nsec;
#endif
}

/* ---------------------------------------------------------------------------------------- */
/* Writer                                                                                     */

struct capture_writer {
    int fd;
    uint8_t *buf;          /* chunk header + payload, written with one call */
    size_t used;           /* payload bytes buffered */
    uint32_t count;        /* records buffered */
    int64_t first_ns, last_ns;
    uint64_t bytes_written;
    uint64_t bytes_lost;   /* received bytes that never reached the file */
    mocap_status error;    /* sticky: after a failed write nothing more is written */
    char cause[128];
    char path[MOCAP_PATH_MAX];
};

static mocap_status writer_error(capture_writer *w)
{
    return mocap_fail(w->error,
                      "capture file %s: not recording since a write failed (%s); %llu received "
                      "bytes not written",
                      w->path, w->cause, (unsigned long long)w->bytes_lost);
}

static mocap_status write_chunk(capture_writer *w)
{
    if (w->error) return writer_error(w);
    if (w->count == 0) return MOCAP_OK;
    uint8_t *h = w->buf;
    memcpy(h, CHUNK_MAGIC, 4);
    put_u32(h + 4, (uint32_t)w->used);
    put_u32(h + 8, w->count);
    put_u32(h + 12, 0);
    put_i64(h + 16, w->first_ns);
    put_i64(h + 24, w->last_ns);
    uint32_t crc = crc32_update(0, h, CHUNK_CRC_OFFSET);
    crc = crc32_update(crc, h + CHUNK_HEADER_SIZE, w->used);
    put_u32(h + CHUNK_CRC_OFFSET, crc);

    size_t total = CHUNK_HEADER_SIZE + w->used;
    int err = file_write_all(w->fd, w->buf, total);
    size_t data_bytes = w->used - (size_t)w->count * RECORD_HEADER_SIZE;
    uint32_t records = w->count;
    w->used = 0;
    w->count = 0;
    if (err == 0) {
        w->bytes_written += total;
        return MOCAP_OK;
    }
    /* The file may now end in a partial chunk; the reader treats it as a truncated tail. */
    w->error = MOCAP_ERR_IO;
    w->bytes_lost += data_bytes;
    mocap_errno_text(err, w->cause, sizeof w->cause);
    return mocap_fail(w->error,
                      "capture file %s: writing a chunk failed: %s; %u records (%llu received "
                      "bytes) lost, recording stopped",
                      w->path, w->cause, (unsigned)records, (unsigned long long)data_bytes);
}

mocap_status capture_writer_open_with_source(const char *path, const char *source,
                                             capture_writer **out)
{
    if (out) *out = NULL;
    if (!path || !out || path[0] == '\0')
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture_writer_open: no path");
    if (strlen(path) >= MOCAP_PATH_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture file %s: path too long", path);

    capture_writer *w = (capture_writer *)calloc(1, sizeof *w);
    if (w) w->buf = (uint8_t *)malloc(CHUNK_BUFFER_SIZE);
    if (!w || !w->buf) {
        free(w);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "capture file %s: out of memory", path);
    }
    snprintf(w->path, sizeof w->path, "%s", path);

    w->fd = file_open(path, 1);
    if (w->fd < 0) {
        mocap_status st = open_failure(path, "cannot create", errno);
        free(w->buf);
        free(w);
        return st;
    }

    uint8_t *h = w->buf; /* the chunk buffer is free: use it to build the file header */
    memset(h, 0, FILE_HEADER_V1_SIZE);
    memcpy(h, FILE_MAGIC, 8);
    put_u16(h + 8, CAPTURE_FORMAT_VERSION);
    put_u16(h + 10, FILE_HEADER_V1_SIZE);
    put_u32(h + 12, 0);
    put_i64(h + 16, wall_clock_unix_ns());
    if (source) {
        size_t n = strlen(source);
        if (n > SOURCE_FIELD - 1) {
            n = SOURCE_FIELD - 1;
            /* Do not cut a UTF-8 sequence in half. */
            while (n > 0 && ((uint8_t)source[n] & 0xC0u) == 0x80u) n--;
        }
        memcpy(h + SOURCE_OFFSET, source, n);
    }
    put_u32(h + FILE_HEADER_V1_SIZE - 4, crc32_update(0, h, FILE_HEADER_V1_SIZE - 4));
    int err = file_write_all(w->fd, h, FILE_HEADER_V1_SIZE);
    if (err != 0) {
        mocap_status st = open_failure(path, "writing the header failed", err);
        if (st != MOCAP_ERR_PERMISSION) st = MOCAP_ERR_IO;
        file_close(w->fd);
        free(w->buf);
        free(w);
        return st;
    }
    w->bytes_written = FILE_HEADER_V1_SIZE;
    *out = w;
    return MOCAP_OK;
}

mocap_status capture_writer_open(const char *path, capture_writer **out)
{
    return capture_writer_open_with_source(path, "", out);
}

mocap_status capture_writer_append(capture_writer *w, int64_t receive_ns, const uint8_t *data,
                                   size_t len)
{
    if (!w || (!data && len > 0))
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture_writer_append: NULL argument");
    if (w->error) {
        w->bytes_lost += len;
        return writer_error(w);
    }
    while (len > 0) {
        size_t piece = len < CAPTURE_MAX_RECORD ? len : CAPTURE_MAX_RECORD;
        if (w->used + RECORD_HEADER_SIZE + piece > CAPTURE_CHUNK_CAPACITY) {
            mocap_status st = write_chunk(w);
            if (st != MOCAP_OK) {
                w->bytes_lost += len; /* this record never got into the buffer */
                return writer_error(w);
            }
        }
        uint8_t *p = w->buf + CHUNK_HEADER_SIZE + w->used;
        put_i64(p, receive_ns);
        put_u16(p + 8, (uint16_t)piece);
        memcpy(p + RECORD_HEADER_SIZE, data, piece);
        if (w->count == 0) w->first_ns = receive_ns;
        w->last_ns = receive_ns;
        w->count++;
        w->used += RECORD_HEADER_SIZE + piece;
        data += piece;
        len -= piece;
    }
    /* No room for even a one-byte record: the buffer is full, write it now. */
    if (w->used + RECORD_HEADER_SIZE + 1 > CAPTURE_CHUNK_CAPACITY) return write_chunk(w);
    return MOCAP_OK;
}

mocap_status capture_writer_poll(capture_writer *w, int64_t now_ns)
{
    if (!w) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture_writer_poll: NULL writer");
    if (w->error) return writer_error(w);
    /* receive_ns is the session clock, which is the monotonic clock now_ns comes from. */
    if (w->count > 0 && now_ns - w->first_ns >= CAPTURE_FLUSH_INTERVAL_NS) return write_chunk(w);
    return MOCAP_OK;
}

mocap_status capture_writer_flush(capture_writer *w)
{
    if (!w) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture_writer_flush: NULL writer");
    return write_chunk(w);
}

uint64_t capture_writer_bytes_written(const capture_writer *w) { return w ? w->bytes_written : 0; }

uint64_t capture_writer_bytes_lost(const capture_writer *w) { return w ? w->bytes_lost : 0; }

mocap_status capture_writer_close(capture_writer *w)
{
    if (!w) return MOCAP_OK;
    mocap_status st = write_chunk(w);
    if (file_close(w->fd) != 0 && st == MOCAP_OK) {
        /* NFS and some FUSE file systems report deferred write errors only here. */
        char text[128];
        mocap_errno_text(errno, text, sizeof text);
        st = mocap_fail(MOCAP_ERR_IO, "capture file %s: close failed: %s", w->path, text);
    }
    free(w->buf);
    free(w);
    return st;
}

/* ---------------------------------------------------------------------------------------- */
/* Reader                                                                                     */

struct capture_reader {
    int fd;
    uint8_t *buf;          /* the current chunk: header + payload */
    int64_t next_offset;   /* file offset of the chunk after the current one */
    size_t payload_len;
    size_t record_offset;  /* within the payload */
    uint32_t records_left;
    uint64_t chunks;
    uint64_t skipped;
    int tail;
    int ended;
    int resyncing;          /* a resync that ran out of time: continues at resync_scan */
    int64_t resync_scan;
    uint64_t resync_damaged;
    int64_t created_unix_ns;
    char source[SOURCE_FIELD];
    char path[MOCAP_PATH_MAX];
};

typedef enum chunk_result {
    CHUNK_VALID,
    CHUNK_EOF,      /* no byte at all at this offset */
    CHUNK_SHORT,    /* the file ends inside it */
    CHUNK_INVALID,  /* bad magic, impossible fields, bad CRC, inconsistent records */
    CHUNK_IO_ERROR
} chunk_result;

static mocap_status read_failure(capture_reader *r, int err)
{
    char text[128];
    mocap_errno_text(err, text, sizeof text);
    return mocap_fail(MOCAP_ERR_IO, "capture file %s: read failed: %s", r->path, text);
}

/* Load the chunk at offset into the buffer and check everything the writer guarantees, so that
 * capture_reader_next never meets a malformed record. */
static chunk_result load_chunk(capture_reader *r, int64_t offset, int *io_err, int *plausible)
{
    size_t got;
    uint8_t *h = r->buf;
    *plausible = 0;
    *io_err = file_read_at(r->fd, offset, h, CHUNK_HEADER_SIZE, &got);
    if (*io_err) return CHUNK_IO_ERROR;
    if (got == 0) return CHUNK_EOF;
    if (got < CHUNK_HEADER_SIZE) return CHUNK_SHORT;
    if (memcmp(h, CHUNK_MAGIC, 4) != 0) return CHUNK_INVALID;
    uint32_t payload_len = get_u32(h + 4);
    uint32_t count = get_u32(h + 8);
    if (payload_len == 0 || payload_len > CAPTURE_CHUNK_CAPACITY || count == 0 ||
        (uint64_t)count * (RECORD_HEADER_SIZE + 1) > payload_len)
        return CHUNK_INVALID;
    *plausible = 1;
    *io_err = file_read_at(r->fd, offset + CHUNK_HEADER_SIZE, h + CHUNK_HEADER_SIZE, payload_len,
                           &got);
    if (*io_err) return CHUNK_IO_ERROR;
    if (got < payload_len) return CHUNK_SHORT;
    uint32_t crc = crc32_update(0, h, CHUNK_CRC_OFFSET);
    crc = crc32_update(crc, h + CHUNK_HEADER_SIZE, payload_len);
    if (crc != get_u32(h + CHUNK_CRC_OFFSET)) return CHUNK_INVALID;

    const uint8_t *p = h + CHUNK_HEADER_SIZE;
    size_t pos = 0;
    int64_t first = 0, last = 0;
    for (uint32_t i = 0; i < count; i++) {
        if (payload_len - pos < RECORD_HEADER_SIZE) return CHUNK_INVALID;
        int64_t ns = get_i64(p + pos);
        uint16_t len = get_u16(p + pos + 8);
        if (len == 0 || len > CAPTURE_MAX_RECORD || payload_len - pos - RECORD_HEADER_SIZE < len)
            return CHUNK_INVALID;
        if (i == 0) first = ns;
        last = ns;
        pos += RECORD_HEADER_SIZE + len;
    }
    if (pos != payload_len || first != get_i64(h + 16) || last != get_i64(h + 24))
        return CHUNK_INVALID;
    r->payload_len = payload_len;
    r->record_offset = 0;
    r->records_left = count;
    r->next_offset = offset + CHUNK_HEADER_SIZE + payload_len;
    return CHUNK_VALID;
}

/* Find the next valid chunk after a damaged one at bad_offset. Candidates are found by their
 * magic and proven by their CRC; the chunk buffer doubles as the scan window. A file made of
 * plausible fake chunk headers costs a 64 KiB read per candidate, so the scan stops at
 * deadline_ns (0: none) with MOCAP_ERR_TIMEOUT and the next call continues where it stopped. */
static mocap_status resync(capture_reader *r, int64_t bad_offset, int64_t deadline_ns)
{
    if (!r->resyncing) {
        r->resyncing = 1;
        r->resync_scan = bad_offset + 1;
        r->resync_damaged = 1;
    }
    int64_t scan = r->resync_scan;
    /* Every call gets past one window or candidate at least, however late it is called. */
    for (int first = 1;; first = 0) {
        if (!first && deadline_ns != 0 && mocap_monotonic_ns() >= deadline_ns) {
            r->resync_scan = scan;
            return MOCAP_ERR_TIMEOUT;
        }
        size_t got;
        int err = file_read_at(r->fd, scan, r->buf, CHUNK_BUFFER_SIZE, &got);
        if (err) return read_failure(r, err);
        size_t hit = SIZE_MAX;
        for (size_t i = 0; i + 4 <= got; i++) {
            if (r->buf[i] == CHUNK_MAGIC[0] && memcmp(r->buf + i, CHUNK_MAGIC, 4) == 0) {
                hit = i;
                break;
            }
        }
        if (hit == SIZE_MAX) {
            if (got < CHUNK_BUFFER_SIZE) break; /* end of file: nothing valid follows */
            scan += (int64_t)(got - 3);          /* keep a magic split across windows */
            continue;
        }
        int64_t candidate = scan + (int64_t)hit;
        int plausible;
        chunk_result res = load_chunk(r, candidate, &err, &plausible);
        if (res == CHUNK_IO_ERROR) return read_failure(r, err);
        if (res == CHUNK_VALID) {
            r->skipped += r->resync_damaged;
            r->chunks++;
            r->resyncing = 0;
            return MOCAP_OK;
        }
        /* A damaged chunk of its own, unless the magic was just bytes inside a payload. */
        if (plausible) r->resync_damaged++;
        scan = candidate + 1;
    }
    r->resyncing = 0;
    r->tail = 1;
    r->ended = 1;
    return MOCAP_ERR_END_OF_STREAM;
}

static mocap_status next_chunk(capture_reader *r, int64_t deadline_ns)
{
    if (r->resyncing) return resync(r, 0, deadline_ns);
    int err, plausible;
    int64_t offset = r->next_offset;
    chunk_result res = load_chunk(r, offset, &err, &plausible);
    switch (res) {
    case CHUNK_VALID: r->chunks++; return MOCAP_OK;
    case CHUNK_EOF: r->ended = 1; return MOCAP_ERR_END_OF_STREAM;
    case CHUNK_IO_ERROR: return read_failure(r, err);
    default: return resync(r, offset, deadline_ns);
    }
}

mocap_status capture_reader_open(const char *path, capture_reader **out)
{
    if (out) *out = NULL;
    if (!path || !out || path[0] == '\0')
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture_reader_open: no path");
    if (strlen(path) >= MOCAP_PATH_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture file %s: path too long", path);
    capture_reader *r = (capture_reader *)calloc(1, sizeof *r);
    if (r) r->buf = (uint8_t *)malloc(CHUNK_BUFFER_SIZE);
    if (!r || !r->buf) {
        free(r);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "capture file %s: out of memory", path);
    }
    snprintf(r->path, sizeof r->path, "%s", path);
    r->fd = file_open(path, 0);
    mocap_status st = MOCAP_OK;
    if (r->fd < 0) {
        st = open_failure(path, "cannot open", errno);
        free(r->buf);
        free(r);
        return st;
    }

    /* The header may be longer than this build knows (up to 64 KiB); the chunk buffer holds it. */
    uint8_t *h = r->buf;
    size_t got;
    int err = file_read_at(r->fd, 0, h, FILE_HEADER_MAX, &got);
    if (err) {
        st = read_failure(r, err);
    } else if (got == 0) {
        st = mocap_fail(MOCAP_ERR_FORMAT, "capture file %s: empty file, not a mocap capture file",
                        path);
    } else if (memcmp(h, FILE_MAGIC, got < 8 ? got : 8) != 0) {
        st = mocap_fail(MOCAP_ERR_FORMAT, "capture file %s: not a mocap capture file", path);
    } else if (got < FILE_HEADER_FIXED) {
        st = mocap_fail(MOCAP_ERR_FORMAT, "capture file %s: truncated header (%u bytes)", path,
                        (unsigned)got);
    } else {
        unsigned version = get_u16(h + 8);
        unsigned header_size = get_u16(h + 10);
        if (version > CAPTURE_FORMAT_VERSION) {
            st = mocap_fail(MOCAP_ERR_FORMAT,
                            "capture file %s: format version %u is newer than this build reads "
                            "(version %u); update the package",
                            path, version, CAPTURE_FORMAT_VERSION);
        } else if (version == 0 || header_size < FILE_HEADER_V1_SIZE) {
            st = mocap_fail(MOCAP_ERR_FORMAT,
                            "capture file %s: invalid header (version %u, header size %u)", path,
                            version, header_size);
        } else if (got < header_size) {
            st = mocap_fail(MOCAP_ERR_FORMAT, "capture file %s: truncated header (%u of %u bytes)",
                            path, (unsigned)got, header_size);
        } else if (crc32_update(0, h, header_size - 4) != get_u32(h + header_size - 4)) {
            st = mocap_fail(MOCAP_ERR_FORMAT, "capture file %s: header CRC mismatch", path);
        } else {
            r->created_unix_ns = get_i64(h + 16);
            memcpy(r->source, h + SOURCE_OFFSET, SOURCE_FIELD);
            r->source[SOURCE_FIELD - 1] = '\0';
            r->next_offset = header_size;
        }
    }
    if (st != MOCAP_OK) {
        file_close(r->fd);
        free(r->buf);
        free(r);
        return st;
    }
    *out = r;
    return MOCAP_OK;
}

mocap_status capture_reader_next(capture_reader *r, int64_t *receive_ns, const uint8_t **data,
                                 size_t *len)
{
    return capture_reader_next_until(r, 0, receive_ns, data, len);
}

mocap_status capture_reader_next_until(capture_reader *r, int64_t deadline_ns, int64_t *receive_ns,
                                       const uint8_t **data, size_t *len)
{
    if (!r || !receive_ns || !data || !len)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "capture_reader_next: NULL argument");
    if (r->ended) return MOCAP_ERR_END_OF_STREAM;
    if (r->records_left == 0) {
        mocap_status st = next_chunk(r, deadline_ns);
        if (st != MOCAP_OK) return st;
    }
    const uint8_t *p = r->buf + CHUNK_HEADER_SIZE + r->record_offset;
    size_t n = get_u16(p + 8);
    *receive_ns = get_i64(p);
    *data = p + RECORD_HEADER_SIZE;
    *len = n;
    r->record_offset += RECORD_HEADER_SIZE + n;
    r->records_left--;
    return MOCAP_OK;
}

int capture_reader_tail(const capture_reader *r) { return r ? r->tail : 0; }

uint64_t capture_reader_chunks(const capture_reader *r) { return r ? r->chunks : 0; }

uint64_t capture_reader_skipped(const capture_reader *r) { return r ? r->skipped : 0; }

const char *capture_reader_source(const capture_reader *r) { return r ? r->source : ""; }

int64_t capture_reader_created_unix_ns(const capture_reader *r)
{
    return r ? r->created_unix_ns : 0;
}

void capture_reader_close(capture_reader *r)
{
    if (!r) return;
    file_close(r->fd);
    free(r->buf);
    free(r);
}
