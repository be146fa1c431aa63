/* Serial port transport on Win32 (COM ports, including USB CDC/CP210x/CH340 adapters): raw
 * 8N1, no flow control, reads bounded by COMMTIMEOUTS, unplug detection. */
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#include <windows.h>

#include "transport.h"

#include "error.h"
#include "platform.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef ERROR_DEVICE_REMOVED
#define ERROR_DEVICE_REMOVED 1617L
#endif
#ifndef ERROR_NO_SUCH_DEVICE
#define ERROR_NO_SUCH_DEVICE 433L
#endif

typedef struct serial_port {
    transport base;     /* first: the transport pointer is the serial_port pointer */
    HANDLE handle;      /* INVALID_HANDLE_VALUE while disconnected */
    uint32_t baud;
    int applied_timeout_ms; /* the read timeout COMMTIMEOUTS currently hold; -1 when unknown */
    char path[MOCAP_PATH_MAX];
} serial_port;

static const char *win_error_text(DWORD code, char *buf, size_t cap)
{
    DWORD n = FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, NULL, code,
                             MAKELANGID(LANG_NEUTRAL, SUBLANG_DEFAULT), buf, (DWORD)cap, NULL);
    if (n == 0) {
        snprintf(buf, cap, "error %lu", (unsigned long)code);
        return buf;
    }
    /* System messages end in ".\r\n", which reads badly inside a longer sentence. */
    while (n > 0 && (buf[n - 1] == '\r' || buf[n - 1] == '\n' || buf[n - 1] == ' ' ||
                     buf[n - 1] == '.'))
        buf[--n] = '\0';
    return buf;
}

/* Errors a USB serial driver returns once its device has been removed. */
static int is_disconnect_error(DWORD code)
{
    switch (code) {
    case ERROR_OPERATION_ABORTED:
    case ERROR_BAD_COMMAND:
    case ERROR_DEVICE_NOT_CONNECTED:
    case ERROR_GEN_FAILURE:
    case ERROR_ACCESS_DENIED:
    case ERROR_INVALID_HANDLE:
    case ERROR_FILE_NOT_FOUND:
    case ERROR_NOT_READY:
    case ERROR_DEV_NOT_EXIST:
    case ERROR_DEVICE_REMOVED:
    case ERROR_NO_SUCH_DEVICE:
        return 1;
    default:
        return 0;
    }
}

static mocap_status not_a_serial_port(const char *path, const char *what)
{
    return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "%s is not a serial port (%s)", path, what);
}

static mocap_status open_error(const char *path, DWORD code)
{
    char text[256];
    switch (code) {
    case ERROR_FILE_NOT_FOUND:
    case ERROR_PATH_NOT_FOUND:
    case ERROR_INVALID_NAME:
    case ERROR_BAD_PATHNAME:
    case ERROR_DEV_NOT_EXIST:
    case ERROR_DEVICE_NOT_CONNECTED:
    case ERROR_NO_SUCH_DEVICE:
        return mocap_fail(MOCAP_ERR_NOT_FOUND,
                          "serial port %s not found (is the receiver plugged in? check Device "
                          "Manager for its COM number)",
                          path);
    case ERROR_ACCESS_DENIED:
        /* COM ports are opened exclusively, so this nearly always means another program. */
        return mocap_fail(MOCAP_ERR_PERMISSION,
                          "access denied opening serial port %s: another program (a terminal, "
                          "the vendor tool) probably has it open; close it and retry",
                          path);
    case ERROR_SHARING_VIOLATION:
    case ERROR_BUSY:
        return mocap_fail(MOCAP_ERR_IO, "serial port %s is busy: another program has it open",
                          path);
    default:
        return mocap_fail(MOCAP_ERR_IO, "cannot open serial port %s: %s", path,
                          win_error_text(code, text, sizeof text));
    }
}

static mocap_status configure(HANDLE h, const char *path, uint32_t baud)
{
    char text[256];
    DCB dcb;
    memset(&dcb, 0, sizeof dcb);
    dcb.DCBlength = sizeof dcb;
    if (!GetCommState(h, &dcb)) {
        DWORD code = GetLastError();
        if (code == ERROR_INVALID_FUNCTION || code == ERROR_NOT_SUPPORTED ||
            code == ERROR_INVALID_HANDLE)
            return not_a_serial_port(path, "the device has no serial settings");
        return mocap_fail(MOCAP_ERR_IO, "serial port %s: cannot read settings: %s", path,
                          win_error_text(code, text, sizeof text));
    }
    /* The driver, not Windows, decides which rates exist; it refuses others in SetCommState. */
    dcb.BaudRate = (DWORD)baud;
    dcb.ByteSize = 8;
    dcb.Parity = NOPARITY;
    dcb.StopBits = ONESTOPBIT;
    dcb.fBinary = TRUE;
    dcb.fParity = FALSE;
    dcb.fOutxCtsFlow = FALSE;
    dcb.fOutxDsrFlow = FALSE;
    dcb.fDtrControl = DTR_CONTROL_ENABLE; /* some adapters only send while DTR is asserted */
    dcb.fDsrSensitivity = FALSE;
    dcb.fTXContinueOnXoff = TRUE;
    dcb.fOutX = FALSE;
    dcb.fInX = FALSE;
    dcb.fErrorChar = FALSE;
    dcb.fNull = FALSE;
    dcb.fRtsControl = RTS_CONTROL_ENABLE;
    /* With fAbortOnError a line error would fail every read until ClearCommError. */
    dcb.fAbortOnError = FALSE;
    if (!SetCommState(h, &dcb)) {
        DWORD code = GetLastError();
        if (code == ERROR_INVALID_PARAMETER || code == ERROR_NOT_SUPPORTED)
            return mocap_fail(MOCAP_ERR_UNSUPPORTED,
                              "serial port %s: baud rate %u is not supported (%s)", path,
                              (unsigned)baud, win_error_text(code, text, sizeof text));
        return mocap_fail(MOCAP_ERR_IO, "serial port %s: cannot apply settings: %s", path,
                          win_error_text(code, text, sizeof text));
    }
    DCB check;
    memset(&check, 0, sizeof check);
    check.DCBlength = sizeof check;
    if (GetCommState(h, &check) && check.BaudRate != (DWORD)baud)
        return mocap_fail(MOCAP_ERR_UNSUPPORTED,
                          "serial port %s: baud rate %u is not supported (the driver set %lu)",
                          path, (unsigned)baud, (unsigned long)check.BaudRate);
    return MOCAP_OK;
}

/* "COM12" needs the \\.\ prefix (only COM1..COM9 resolve without it); names already in the
 * device namespace are kept. */
static void device_name(const char *path, char *out, size_t cap)
{
    if (strncmp(path, "\\\\.\\", 4) == 0 || strncmp(path, "\\\\?\\", 4) == 0)
        snprintf(out, cap, "%s", path);
    else
        snprintf(out, cap, "\\\\.\\%s", path);
}

static mocap_status open_port(serial_port *port)
{
    char device[MOCAP_PATH_MAX + 8];
    wchar_t wide_device[MOCAP_PATH_MAX + 8];
    device_name(port->path, device, sizeof device);
    if (mocap_utf8_to_wide(device, wide_device, MOCAP_PATH_MAX + 8) != 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port %s: not a valid UTF-8 name",
                          port->path);
    HANDLE h = CreateFileW(wide_device, GENERIC_READ | GENERIC_WRITE, 0 /* exclusive */, NULL,
                           OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, NULL);
    if (h == INVALID_HANDLE_VALUE) return open_error(port->path, GetLastError());
    if (GetFileType(h) != FILE_TYPE_CHAR) {
        CloseHandle(h);
        return not_a_serial_port(port->path, "not a character device");
    }
    /* A larger driver queue rides out scheduling hiccups of the reader thread at 921600 baud;
     * drivers that do not support it keep their default. */
    (void)SetupComm(h, 65536, 4096);
    mocap_status status = configure(h, port->path, port->baud);
    if (status != MOCAP_OK) {
        CloseHandle(h);
        return status;
    }
    /* Bytes queued before this open are stale: their receive time would be wrong. */
    (void)PurgeComm(h, PURGE_RXABORT | PURGE_RXCLEAR | PURGE_TXABORT | PURGE_TXCLEAR);
    DWORD errors = 0;
    (void)ClearCommError(h, &errors, NULL);
    port->handle = h;
    port->applied_timeout_ms = -1;
    return MOCAP_OK;
}

static mocap_status disconnected(serial_port *port, DWORD code)
{
    char text[256];
    if (port->handle != INVALID_HANDLE_VALUE) {
        CloseHandle(port->handle);
        port->handle = INVALID_HANDLE_VALUE;
    }
    return mocap_fail(MOCAP_ERR_DISCONNECTED, "serial port %s disconnected (%s)", port->path,
                      win_error_text(code, text, sizeof text));
}

/* ReadIntervalTimeout = ReadTotalTimeoutMultiplier = MAXDWORD with a constant in (0, MAXDWORD)
 * makes ReadFile return as soon as any byte is there, or after the constant with nothing. */
static BOOL apply_timeout(serial_port *port, int timeout_ms)
{
    if (port->applied_timeout_ms == timeout_ms) return TRUE;
    COMMTIMEOUTS ct;
    memset(&ct, 0, sizeof ct);
    ct.ReadIntervalTimeout = MAXDWORD;
    if (timeout_ms > 0) {
        ct.ReadTotalTimeoutMultiplier = MAXDWORD;
        ct.ReadTotalTimeoutConstant = (DWORD)timeout_ms;
    } /* else: interval MAXDWORD and zero totals return at once with what is queued */
    ct.WriteTotalTimeoutConstant = 1000;
    if (!SetCommTimeouts(port->handle, &ct)) {
        port->applied_timeout_ms = -1;
        return FALSE;
    }
    port->applied_timeout_ms = timeout_ms;
    return TRUE;
}

static mocap_status serial_read(transport *t, uint8_t *buf, size_t cap, int timeout_ms,
                                size_t *got, int64_t *receive_ns)
{
    serial_port *port = (serial_port *)t;
    char text[256];
    if (got) *got = 0;
    if (!buf || !got || cap == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port %s: invalid read arguments",
                          port->path);
    if (port->handle == INVALID_HANDLE_VALUE)
        return mocap_fail(MOCAP_ERR_DISCONNECTED,
                          "serial port %s is disconnected (reopen it after replugging)", port->path);
    if (timeout_ms < 0) timeout_ms = 0;
    const int64_t deadline = mocap_monotonic_ns() + (int64_t)timeout_ms * 1000000LL;
    const DWORD want = cap > (size_t)MAXDWORD ? MAXDWORD : (DWORD)cap;

    for (;;) {
        int64_t left_ns = deadline - mocap_monotonic_ns();
        int wait_ms = left_ns <= 0 ? 0 : (int)((left_ns + 999999) / 1000000);
        if (!apply_timeout(port, wait_ms)) {
            DWORD code = GetLastError();
            if (is_disconnect_error(code)) return disconnected(port, code);
            return mocap_fail(MOCAP_ERR_IO, "serial port %s: cannot set read timeout: %s",
                              port->path, win_error_text(code, text, sizeof text));
        }
        DWORD n = 0;
        if (!ReadFile(port->handle, buf, want, &n, NULL)) {
            DWORD code = GetLastError();
            if (is_disconnect_error(code)) return disconnected(port, code);
            return mocap_fail(MOCAP_ERR_IO, "serial port %s: read failed: %s", port->path,
                              win_error_text(code, text, sizeof text));
        }
        if (n > 0) {
            *got = (size_t)n;
            if (receive_ns) *receive_ns = mocap_monotonic_ns();
            return MOCAP_OK;
        }
        /* Some drivers (usbser.sys) keep completing reads with zero bytes after the device is
         * removed instead of failing them; the port status call does fail. */
        DWORD errors = 0;
        COMSTAT stat;
        if (!ClearCommError(port->handle, &errors, &stat)) {
            DWORD code = GetLastError();
            if (is_disconnect_error(code)) return disconnected(port, code);
        }
        if (mocap_monotonic_ns() >= deadline)
            return mocap_fail(MOCAP_ERR_TIMEOUT, "serial port %s: no data within %d ms",
                              port->path, timeout_ms);
        Sleep(1); /* an early empty completion: wait out the rest without spinning */
    }
}

static mocap_status serial_reopen(transport *t)
{
    serial_port *port = (serial_port *)t;
    if (port->handle != INVALID_HANDLE_VALUE) {
        CloseHandle(port->handle);
        port->handle = INVALID_HANDLE_VALUE;
    }
    return open_port(port);
}

static void serial_close(transport *t)
{
    serial_port *port = (serial_port *)t;
    if (port->handle != INVALID_HANDLE_VALUE) CloseHandle(port->handle);
    free(port);
}

static const transport_ops serial_ops = {serial_read, serial_reopen, serial_close, NULL};

mocap_status transport_open_serial(const char *path, uint32_t baud, transport **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port: NULL output pointer");
    *out = NULL;
    if (!path || !path[0])
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port: no port name given");
    if (strlen(path) >= MOCAP_PATH_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port name is too long (%u bytes)",
                          (unsigned)strlen(path));
    if (baud == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port %s: baud rate 0 is invalid",
                          path);

    serial_port *port = (serial_port *)calloc(1, sizeof *port);
    if (!port) return mocap_fail(MOCAP_ERR_NO_MEMORY, "serial port %s: out of memory", path);
    port->base.ops = &serial_ops;
    port->handle = INVALID_HANDLE_VALUE;
    port->baud = baud;
    port->applied_timeout_ms = -1;
    snprintf(port->path, sizeof port->path, "%s", path);
    snprintf(port->base.description, sizeof port->base.description, "serial port %s", path);

    mocap_status status = open_port(port);
    if (status != MOCAP_OK) {
        free(port);
        return status;
    }
    *out = &port->base;
    return MOCAP_OK;
}
