/* Thread-local error text behind mocap_last_error(). */
#ifndef MOCAP_ERROR_H
#define MOCAP_ERROR_H

#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Record a printf-style message for the calling thread and return status, so that failing
 * functions can `return mocap_fail(MOCAP_ERR_IO, "port %s: %s", path, strerror(e));`. */
mocap_status mocap_fail(mocap_status status, const char *fmt, ...)
#if defined(__MINGW32__)
    /* MinGW checks printf formats against the old msvcrt (no %zu) unless told the C99 stdio
     * (__USE_MINGW_ANSI_STDIO, set by CMake) is used. */
    __attribute__((format(gnu_printf, 2, 3)))
#elif defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
void mocap_clear_error(void);
/* Copy the calling thread's error text into buf (always NUL-terminated). */
void mocap_copy_error(char *buf, size_t cap);
/* Describe an errno value portably (strerror_r wrapper). */
const char *mocap_errno_text(int err, char *buf, size_t cap);

#ifdef __cplusplus
}
#endif
#endif
