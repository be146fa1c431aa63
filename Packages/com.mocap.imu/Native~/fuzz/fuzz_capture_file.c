/* libFuzzer target for the raw capture reader (docs/capture-format.md).
 *
 * Invariants, any violation aborts:
 *  1. Reading ends with END_OF_STREAM after records of 1..CAPTURE_MAX_RECORD bytes; a refused
 *     file sets a non-empty error text.
 *  2. The records read, written again with the capture writer (same source text), read back as
 *     exactly the same records, times and source, with a clean tail and nothing skipped. */
#include "capture_file.h"
#include "fuzz_file_support.h"

#define MAX_RECORDS 4096

typedef struct record_copy {
    int64_t receive_ns;
    size_t offset, length;
} record_copy;

static record_copy records[MAX_RECORDS];
static uint8_t bytes[1 << 20];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char path[600], rewritten[600], source[256];
    fuzz_write_file("input.cap", data, size, path, sizeof path);

    capture_reader *r = NULL;
    if (capture_reader_open(path, &r) != MOCAP_OK) {
        fuzz_check(r == NULL);
        fuzz_check(mocap_last_error() != NULL && mocap_last_error()[0] != '\0');
        return 0;
    }
    snprintf(source, sizeof source, "%s", capture_reader_source(r));
    size_t count = 0, used = 0;
    int64_t t;
    const uint8_t *rec;
    size_t len;
    mocap_status st;
    while ((st = capture_reader_next(r, &t, &rec, &len)) == MOCAP_OK) {
        fuzz_check(len >= 1 && len <= CAPTURE_MAX_RECORD);
        fuzz_check(count < MAX_RECORDS && used + len <= sizeof bytes);
        records[count] = (record_copy){t, used, len};
        memcpy(bytes + used, rec, len);
        used += len;
        count++;
    }
    fuzz_check(st == MOCAP_ERR_END_OF_STREAM);
    capture_reader_close(r);

    snprintf(rewritten, sizeof rewritten, "%s/rewritten.cap", fuzz_scratch_dir());
    capture_writer *w = NULL;
    fuzz_check(capture_writer_open_with_source(rewritten, source, &w) == MOCAP_OK);
    for (size_t i = 0; i < count; i++)
        fuzz_check(capture_writer_append(w, records[i].receive_ns, bytes + records[i].offset,
                                         records[i].length) == MOCAP_OK);
    fuzz_check(capture_writer_close(w) == MOCAP_OK);

    fuzz_check(capture_reader_open(rewritten, &r) == MOCAP_OK);
    fuzz_check(strcmp(source, capture_reader_source(r)) == 0);
    for (size_t i = 0; i < count; i++) {
        fuzz_check(capture_reader_next(r, &t, &rec, &len) == MOCAP_OK);
        fuzz_check(t == records[i].receive_ns && len == records[i].length);
        fuzz_check(memcmp(rec, bytes + records[i].offset, len) == 0);
    }
    fuzz_check(capture_reader_next(r, &t, &rec, &len) == MOCAP_ERR_END_OF_STREAM);
    fuzz_check(capture_reader_tail(r) == 0 && capture_reader_skipped(r) == 0);
    capture_reader_close(r);
    return 0;
}
