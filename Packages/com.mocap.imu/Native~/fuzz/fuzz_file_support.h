/* Shared by the file-format fuzz targets: a private scratch directory and a helper that puts the
 * fuzzer's bytes into a real file there, because the readers under test take paths. */
#ifndef MOCAP_FUZZ_FILE_SUPPORT_H
#define MOCAP_FUZZ_FILE_SUPPORT_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char fuzz_dir[512];

static void fuzz_remove_dir(void)
{
    if (fuzz_dir[0]) {
        char cmd[600];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", fuzz_dir);
        if (system(cmd) != 0) { /* best effort */
        }
    }
}

static void fuzz_check(int ok)
{
    if (!ok) abort();
}

/* Create the scratch directory once (under $TMPDIR or /tmp), removed at exit. */
static const char *fuzz_scratch_dir(void)
{
    if (!fuzz_dir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(fuzz_dir, sizeof fuzz_dir, "%s/mocap-fuzz-XXXXXX", base && base[0] ? base : "/tmp");
        fuzz_check(mkdtemp(fuzz_dir) != NULL);
        atexit(fuzz_remove_dir);
    }
    return fuzz_dir;
}

/* Write data to <scratch>/<name>; the path goes to path (size cap). */
static void fuzz_write_file(const char *name, const uint8_t *data, size_t size, char *path, size_t cap)
{
    snprintf(path, cap, "%s/%s", fuzz_scratch_dir(), name);
    FILE *f = fopen(path, "wb");
    fuzz_check(f != NULL);
    fuzz_check(size == 0 || fwrite(data, 1, size, f) == size);
    fuzz_check(fclose(f) == 0);
}

#endif
