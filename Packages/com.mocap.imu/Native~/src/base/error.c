#include "error.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#if defined(_MSC_VER)
#define MOCAP_THREAD_LOCAL __declspec(thread)
#else
#define MOCAP_THREAD_LOCAL _Thread_local
#endif

static MOCAP_THREAD_LOCAL char last_error_text[512];

mocap_status mocap_fail(mocap_status status, const char *fmt, ...)
{
    va_list args;
    va_start(args, fmt);
    vsnprintf(last_error_text, sizeof last_error_text, fmt, args);
    va_end(args);
    return status;
}

void mocap_clear_error(void) { last_error_text[0] = '\0'; }

void mocap_copy_error(char *buf, size_t cap)
{
    if (!buf || cap == 0) return;
    snprintf(buf, cap, "%s", last_error_text);
}

const char *mocap_errno_text(int err, char *buf, size_t cap)
{
#if defined(_WIN32)
    strerror_s(buf, cap, err);
#else
    /* strerror is not thread-safe; glibc's GNU strerror_r may return a static string instead. */
    snprintf(buf, cap, "error %d", err);
#if defined(__GLIBC__) && defined(_GNU_SOURCE)
    const char *text = strerror_r(err, buf, cap);
    if (text != buf) snprintf(buf, cap, "%s", text);
#else
    if (strerror_r(err, buf, cap) != 0) snprintf(buf, cap, "error %d", err);
#endif
#endif
    return buf;
}

const char *mocap_last_error(void) { return last_error_text; }

const char *mocap_status_name(mocap_status status)
{
    switch (status) {
    case MOCAP_OK: return "MOCAP_OK";
    case MOCAP_ERR_INVALID_ARGUMENT: return "MOCAP_ERR_INVALID_ARGUMENT";
    case MOCAP_ERR_NOT_FOUND: return "MOCAP_ERR_NOT_FOUND";
    case MOCAP_ERR_PERMISSION: return "MOCAP_ERR_PERMISSION";
    case MOCAP_ERR_IO: return "MOCAP_ERR_IO";
    case MOCAP_ERR_DISCONNECTED: return "MOCAP_ERR_DISCONNECTED";
    case MOCAP_ERR_FORMAT: return "MOCAP_ERR_FORMAT";
    case MOCAP_ERR_STATE: return "MOCAP_ERR_STATE";
    case MOCAP_ERR_UNSUPPORTED: return "MOCAP_ERR_UNSUPPORTED";
    case MOCAP_ERR_NO_MEMORY: return "MOCAP_ERR_NO_MEMORY";
    case MOCAP_ERR_BAD_CALIBRATION: return "MOCAP_ERR_BAD_CALIBRATION";
    case MOCAP_ERR_NO_DATA: return "MOCAP_ERR_NO_DATA";
    case MOCAP_ERR_END_OF_STREAM: return "MOCAP_ERR_END_OF_STREAM";
    case MOCAP_ERR_TIMEOUT: return "MOCAP_ERR_TIMEOUT";
    default: return "MOCAP_ERR_UNKNOWN";
    }
}
