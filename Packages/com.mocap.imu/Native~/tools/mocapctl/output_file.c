/* Output files of mocapctl's commands (output_file.h). */
#include "output_file.h"

#include <errno.h>
#include <string.h>

#include "platform.h"

int output_close(FILE **f, const char *path)
{
    if (!*f) return 0;
    const int bad = ferror(*f) != 0;
    const int close_failed = fclose(*f) != 0;
    *f = NULL;
    if (!bad && !close_failed) return 0;
    fprintf(stderr, "mocapctl: writing %s failed (%s): the file is incomplete\n", path,
            strerror(errno));
    return 1;
}

int file_exists(const char *path)
{
    FILE *f = mocap_fopen(path, "rb");
    if (!f) return 0;
    fclose(f);
    return 1;
}

long file_size(const char *path)
{
    FILE *f = mocap_fopen(path, "rb");
    if (!f) return -1;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fclose(f);
    return n;
}
