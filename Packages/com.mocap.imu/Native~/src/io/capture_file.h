/* Raw capture files: the exact bytes received, with receive timestamps, append-only, in chunks
 * each protected by a CRC-32, flushed to the OS at least every CAPTURE_FLUSH_INTERVAL_NS. A file
 * cut off by a crash replays up to its last complete chunk. Format: docs/capture-format.md. */
#ifndef MOCAP_CAPTURE_FILE_H
#define MOCAP_CAPTURE_FILE_H

#include <stddef.h>
#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CAPTURE_FLUSH_INTERVAL_NS 100000000LL  /* 100 ms */
#define CAPTURE_CHUNK_CAPACITY 65536           /* payload bytes per chunk at most */
#define CAPTURE_MAX_RECORD 4096                /* bytes in one record at most */

typedef struct capture_writer capture_writer;

/* Create (truncate) path and write the file header. */
mocap_status capture_writer_open(const char *path, capture_writer **out);
/* Same, recording a free-form description of the source in the header (e.g. the transport
 * description "serial port /dev/ttyUSB0"; UTF-8, cut to 255 bytes). */
mocap_status capture_writer_open_with_source(const char *path, const char *source,
                                             capture_writer **out);
/* Buffer one record: bytes received at receive_ns (session clock, ns). Records longer than
 * CAPTURE_MAX_RECORD are split. Writes a chunk when the buffer fills. */
mocap_status capture_writer_append(capture_writer *w, int64_t receive_ns, const uint8_t *data,
                                   size_t len);
/* Write the buffered records as a chunk if the oldest is older than the flush interval at
 * now_ns (monotonic ns). Call at least every few tens of ms. */
mocap_status capture_writer_poll(capture_writer *w, int64_t now_ns);
/* Write the buffered records as a chunk now. */
mocap_status capture_writer_flush(capture_writer *w);
uint64_t capture_writer_bytes_written(const capture_writer *w);
/* Received bytes that will never reach the file: those of a chunk whose write failed and all
 * appended after it (the writer stops at the first write error; every call then fails). */
uint64_t capture_writer_bytes_lost(const capture_writer *w);
/* Flush, close and free. Returns the status of the final flush. NULL accepted. */
mocap_status capture_writer_close(capture_writer *w);

typedef struct capture_reader capture_reader;

mocap_status capture_reader_open(const char *path, capture_reader **out);
/* Next record. *data stays valid until the next call. MOCAP_ERR_END_OF_STREAM at the end of the
 * last complete chunk (also when the tail is truncated or corrupt: see capture_reader_tail). */
mocap_status capture_reader_next(capture_reader *r, int64_t *receive_ns, const uint8_t **data,
                                 size_t *len);
/* capture_reader_next that gives up at deadline_ns (the monotonic clock; 0: never) while it is
 * skipping damaged data, returning MOCAP_ERR_TIMEOUT; the next call continues the search. A
 * replay's reader thread uses it so that a long damaged stretch cannot hold up a stop. */
mocap_status capture_reader_next_until(capture_reader *r, int64_t deadline_ns, int64_t *receive_ns,
                                       const uint8_t **data, size_t *len);
/* 0: ended cleanly; 1: a truncated or corrupt tail was ignored. */
int capture_reader_tail(const capture_reader *r);
/* Valid chunks read so far. */
uint64_t capture_reader_chunks(const capture_reader *r);
/* Damaged chunks skipped so far because a valid chunk followed them (a damaged tail is not
 * counted here: see capture_reader_tail). */
uint64_t capture_reader_skipped(const capture_reader *r);
/* Header fields: the source description ("" if none) and the creation time (Unix ns, UTC). */
const char *capture_reader_source(const capture_reader *r);
int64_t capture_reader_created_unix_ns(const capture_reader *r);
void capture_reader_close(capture_reader *r);

#ifdef __cplusplus
}
#endif
#endif
