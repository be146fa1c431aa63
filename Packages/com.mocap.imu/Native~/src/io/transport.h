/* Byte sources: a serial port (POSIX termios or Win32), a HID receiver (hidapi) or a capture
 * file replay. A transport is used by one reader thread. Reads wait at most timeout_ms so the
 * thread can notice a stop request. */
#ifndef MOCAP_TRANSPORT_H
#define MOCAP_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct transport transport;

typedef struct transport_ops {
    /* Read up to cap bytes. Returns MOCAP_OK with *got > 0; MOCAP_ERR_TIMEOUT when nothing came
     * within timeout_ms; MOCAP_ERR_DISCONNECTED when the device went away (the transport closes
     * its handle; call reopen); MOCAP_ERR_END_OF_STREAM at the end of a replay; MOCAP_ERR_IO. */
    mocap_status (*read)(transport *t, uint8_t *buf, size_t cap, int timeout_ms, size_t *got,
                         int64_t *receive_ns);
    /* Try once to open the device again after a disconnect. */
    mocap_status (*reopen)(transport *t);
    void (*close)(transport *t);
    /* Replay only (NULL for devices): damaged chunks passed over so far, and whether the file
     * turned out to end in a damaged or incomplete chunk. Called by the reading thread. */
    void (*damage)(const transport *t, uint64_t *chunks_skipped, int32_t *tail_damaged);
} transport_ops;

struct transport {
    const transport_ops *ops;
    char description[MOCAP_PATH_MAX + 32]; /* e.g. "serial port /dev/ttyUSB0" */
};

/* Any baud rate the OS accepts (termios2/BOTHER on Linux for non-standard rates). Errors name
 * the port and the cause (not found, permission denied, not a tty, unsupported baud). */
mocap_status transport_open_serial(const char *path, uint32_t baud, transport **out);
/* path (hidraw path) if non-empty, else the first device with vendor/product id. */
mocap_status transport_open_hid(const char *path, uint16_t vendor_id, uint16_t product_id,
                                transport **out);
/* Records come back with their recorded receive time, so a replay's frames carry the recorded
 * timeline whatever the pace. realtime paces delivery (the first record at once, the others
 * after their recorded spacing divided by speed); otherwise as fast as the reader asks. */
mocap_status transport_open_replay(const char *path, int realtime, double speed, transport **out);

static inline mocap_status transport_read(transport *t, uint8_t *buf, size_t cap, int timeout_ms,
                                          size_t *got, int64_t *receive_ns)
{
    return t->ops->read(t, buf, cap, timeout_ms, got, receive_ns);
}
static inline mocap_status transport_reopen(transport *t) { return t->ops->reopen(t); }
static inline void transport_close(transport *t)
{
    if (t) t->ops->close(t);
}

#ifdef __cplusplus
}
#endif
#endif
