/* Files mocapctl's commands write and look at (UTF-8 paths, through the engine's mocap_fopen). */
#ifndef MOCAPCTL_OUTPUT_FILE_H
#define MOCAPCTL_OUTPUT_FILE_H

#include <stdio.h>

/* Closes an output file (CSV, JSON lines) and says whether everything reached it: stdio reports
 * a full disk only through ferror and fclose. 0 when complete, else 1 after saying so on stderr;
 * *f becomes NULL either way (a NULL *f is complete). */
int output_close(FILE **f, const char *path);

/* 1 when `path` opens for reading. */
int file_exists(const char *path);

/* Size in bytes, or -1 when the file does not open. */
long file_size(const char *path);

#endif
