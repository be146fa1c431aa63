/* HID transport through hidapi: input reports are concatenated into one byte stream (the HiPNUC
 * decoder finds frame boundaries itself). Built as a stub when hidapi is not available. */
#include "transport.h"

#include "error.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if !defined(MOCAP_HAVE_HIDAPI)

mocap_status transport_open_hid(const char *path, uint16_t vendor_id, uint16_t product_id,
                                transport **out)
{
    /* A bad selection is the caller's error in every build, so it is named as such here too. */
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "HID device: NULL output pointer");
    *out = NULL;
    if (!(path && path[0]) && vendor_id == 0 && product_id == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "HID device: give a device path or a vendor/product id");
    return mocap_fail(MOCAP_ERR_UNSUPPORTED,
                      "HID transport unavailable: the engine was built without hidapi");
}

#else

#include "platform.h"

#include <hidapi.h>
#include <wchar.h>

#if !defined(_WIN32)
#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

/* hidraw hands out one report per read and drops what does not fit the buffer, so reports are
 * read into a buffer that holds the largest one (hidraw's limit on older kernels). */
#define HID_REPORT_CAP 4096
/* Bounds how many already-queued reports one read call gathers. */
#define HID_BATCH_REPORTS 64

typedef struct hid_port {
    transport base; /* first: the transport pointer is the hid_port pointer */
    hid_device *dev; /* NULL while disconnected */
    char path[MOCAP_PATH_MAX];
    uint16_t vendor_id;
    uint16_t product_id;
    char label[MOCAP_PATH_MAX + 16]; /* "HID device 0483:5740" or "HID device /dev/hidraw3" */
    uint8_t report[HID_REPORT_CAP];
    size_t report_len;
    size_t report_pos; /* bytes of report already handed out */
    int64_t report_ns;
    int failed;        /* a read error is waiting to be reported */
    char failure[512]; /* its text */
} hid_port;

/* hidapi needs hid_init once per process, and its global error text (hid_error(NULL)) is
 * shared, so opens are serialised. A spin lock on an atomic int needs no initialisation of its
 * own, unlike a mutex. */
static mocap_atomic_int hid_lock;
static int hid_initialised;

static void hid_global_lock(void)
{
    while (mocap_atomic_exchange_int(&hid_lock, 1) != 0) mocap_sleep_ms(1);
}

static void hid_global_unlock(void) { mocap_atomic_store_int(&hid_lock, 0); }

/* hidapi reports errors as wide strings; messages here are narrow. */
static const char *narrow(const wchar_t *wide, char *buf, size_t cap)
{
    if (!wide || !wide[0]) {
        snprintf(buf, cap, "no details from hidapi");
        return buf;
    }
    size_t i = 0;
    for (; wide[i] && i + 1 < cap; ++i)
        buf[i] = (wide[i] >= 0x20 && wide[i] < 0x7f) ? (char)wide[i] : '?';
    buf[i] = '\0';
    return buf;
}

static int is_filesystem_path(const char *path) { return path[0] == '/'; }

/* hidapi does not say why an open failed in a way a program can act on; look at the node. */
static mocap_status open_failure(const hid_port *port, const char *device_path)
{
    char detail[256];
    narrow(hid_error(NULL), detail, sizeof detail);
#if !defined(_WIN32)
    if (is_filesystem_path(device_path)) {
        struct stat st;
        if (stat(device_path, &st) != 0 && (errno == ENOENT || errno == ENOTDIR))
            return mocap_fail(MOCAP_ERR_NOT_FOUND, "%s not found (is the receiver plugged in?)",
                              port->label);
        if (access(device_path, R_OK | W_OK) != 0 && (errno == EACCES || errno == EPERM))
            return mocap_fail(MOCAP_ERR_PERMISSION,
                              "permission denied opening %s (%s): add a udev rule giving your "
                              "user read/write access to the hidraw node",
                              port->label, device_path);
    }
#endif
    return mocap_fail(MOCAP_ERR_IO, "cannot open %s (%s): %s", port->label, device_path, detail);
}

static mocap_status open_device_locked(hid_port *port)
{
    if (!hid_initialised) {
        if (hid_init() != 0) {
            char detail[256];
            return mocap_fail(MOCAP_ERR_IO, "cannot open %s: hidapi initialisation failed: %s",
                              port->label, narrow(hid_error(NULL), detail, sizeof detail));
        }
        hid_initialised = 1;
    }

    char device_path[MOCAP_PATH_MAX];
    if (port->path[0]) {
#if !defined(_WIN32)
        if (is_filesystem_path(port->path)) {
            struct stat st;
            if (stat(port->path, &st) != 0) {
                if (errno == ENOENT || errno == ENOTDIR)
                    return mocap_fail(MOCAP_ERR_NOT_FOUND,
                                      "%s not found (is the receiver plugged in?)", port->label);
            } else if (!S_ISCHR(st.st_mode)) {
                return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "%s is not a HID device node",
                                  port->label);
            }
        }
#endif
        snprintf(device_path, sizeof device_path, "%s", port->path);
    } else {
        /* Enumerate rather than hid_open() so "absent" and "present but refused" differ. */
        struct hid_device_info *list = hid_enumerate(port->vendor_id, port->product_id);
        if (!list || !list->path) {
            hid_free_enumeration(list);
            return mocap_fail(MOCAP_ERR_NOT_FOUND, "%s not found (is the receiver plugged in?)",
                              port->label);
        }
        snprintf(device_path, sizeof device_path, "%s", list->path);
        hid_free_enumeration(list);
    }

    hid_device *dev = hid_open_path(device_path);
    if (!dev) return open_failure(port, device_path);
    /* Reads wait in hid_read_timeout; the handle itself stays blocking. */
    (void)hid_set_nonblocking(dev, 0);
    port->dev = dev;
    port->report_len = 0;
    port->report_pos = 0;
    port->failed = 0;
    return MOCAP_OK;
}

static mocap_status open_device(hid_port *port)
{
    hid_global_lock();
    mocap_status status = open_device_locked(port);
    hid_global_unlock();
    return status;
}

static void close_device(hid_port *port)
{
    if (port->dev) hid_close(port->dev);
    port->dev = NULL;
    port->report_len = 0;
    port->report_pos = 0;
}

/* Hands out what is left of the current report. */
static size_t take_pending(hid_port *port, uint8_t *buf, size_t cap)
{
    size_t n = port->report_len - port->report_pos;
    if (n > cap) n = cap;
    memcpy(buf, port->report + port->report_pos, n);
    port->report_pos += n;
    return n;
}

/* Returns the report length, 0 on timeout, -1 after recording the failure. */
static int read_report(hid_port *port, int timeout_ms)
{
    int n = hid_read_timeout(port->dev, port->report, sizeof port->report, timeout_ms);
    if (n < 0) {
        char detail[200];
        snprintf(port->failure, sizeof port->failure, "%s disconnected: %s", port->label,
                 narrow(hid_error(port->dev), detail, sizeof detail));
        port->failed = 1;
        close_device(port);
        return -1;
    }
    port->report_len = (size_t)n;
    port->report_pos = 0;
    port->report_ns = mocap_monotonic_ns();
    return n;
}

static mocap_status hid_read_bytes(transport *t, uint8_t *buf, size_t cap, int timeout_ms,
                                   size_t *got, int64_t *receive_ns)
{
    hid_port *port = (hid_port *)t;
    if (got) *got = 0;
    if (!buf || !got || cap == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "%s: invalid read arguments", port->label);
    if (timeout_ms < 0) timeout_ms = 0;

    size_t total = 0;
    int64_t first_ns = 0;
    if (port->report_pos < port->report_len) {
        first_ns = port->report_ns;
        total = take_pending(port, buf, cap);
    } else if (port->failed) {
        port->failed = 0;
        return mocap_fail(MOCAP_ERR_DISCONNECTED, "%s", port->failure);
    } else if (!port->dev) {
        return mocap_fail(MOCAP_ERR_DISCONNECTED,
                          "%s is disconnected (reopen it after replugging)", port->label);
    } else {
        int n = read_report(port, timeout_ms);
        if (n < 0) {
            port->failed = 0;
            return mocap_fail(MOCAP_ERR_DISCONNECTED, "%s", port->failure);
        }
        if (n == 0)
            return mocap_fail(MOCAP_ERR_TIMEOUT, "%s: no data within %d ms", port->label,
                              timeout_ms);
        first_ns = port->report_ns;
        total = take_pending(port, buf, cap);
    }

    /* Gather reports that are already queued; a failure here surfaces on the next call so the
     * bytes in hand are not lost. */
    for (int i = 0; i < HID_BATCH_REPORTS && total < cap && port->dev; ++i) {
        if (read_report(port, 0) <= 0) break;
        total += take_pending(port, buf + total, cap - total);
    }
    *got = total;
    if (receive_ns) *receive_ns = first_ns;
    return MOCAP_OK;
}

static mocap_status hid_reopen(transport *t)
{
    hid_port *port = (hid_port *)t;
    close_device(port);
    port->failed = 0;
    return open_device(port);
}

static void hid_close_transport(transport *t)
{
    hid_port *port = (hid_port *)t;
    close_device(port);
    free(port);
}

static const transport_ops hid_ops = {hid_read_bytes, hid_reopen, hid_close_transport, NULL};

mocap_status transport_open_hid(const char *path, uint16_t vendor_id, uint16_t product_id,
                                transport **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "HID device: NULL output pointer");
    *out = NULL;
    const int by_path = path && path[0];
    if (!by_path && vendor_id == 0 && product_id == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                          "HID device: give a device path or a vendor/product id");
    if (by_path && strlen(path) >= MOCAP_PATH_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "HID device path is too long (%zu bytes)",
                          strlen(path));

    hid_port *port = (hid_port *)calloc(1, sizeof *port);
    if (!port) return mocap_fail(MOCAP_ERR_NO_MEMORY, "HID device: out of memory");
    port->base.ops = &hid_ops;
    port->vendor_id = vendor_id;
    port->product_id = product_id;
    if (by_path) {
        snprintf(port->path, sizeof port->path, "%s", path);
        snprintf(port->label, sizeof port->label, "HID device %s", path);
    } else {
        snprintf(port->label, sizeof port->label, "HID device %04x:%04x", (unsigned)vendor_id,
                 (unsigned)product_id);
    }
    snprintf(port->base.description, sizeof port->base.description, "%s", port->label);

    mocap_status status = open_device(port);
    if (status != MOCAP_OK) {
        free(port);
        return status;
    }
    *out = &port->base;
    return MOCAP_OK;
}

#endif /* MOCAP_HAVE_HIDAPI */
