/* Serial port transport on POSIX termios (Linux, macOS, BSD): raw 8N1, no flow control, any
 * baud rate the OS accepts, poll()-based reads with a timeout, unplug detection. */
#if defined(__linux__) && !defined(_GNU_SOURCE)
#define _GNU_SOURCE /* CRTSCTS, flock, O_CLOEXEC on older glibc */
#endif
#if defined(__APPLE__) && !defined(_DARWIN_C_SOURCE)
#define _DARWIN_C_SOURCE
#endif

#include "transport.h"

#include "error.h"
#include "platform.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#if defined(__APPLE__)
#include <IOKit/serial/ioss.h> /* IOSSIOSPEED */
#endif

/* Linux: a rate without a Bxxx constant needs the kernel's termios2 with BOTHER. Including
 * <asm/termbits.h> would redefine struct termios and clash with <termios.h>, so the kernel
 * layout is declared here. Only architectures using the asm-generic layout (NCCS 19, 'T' 0x2A
 * ioctls) are listed; elsewhere non-standard rates report MOCAP_ERR_UNSUPPORTED. The ioctl
 * number encodes the struct size, so a layout mismatch would be refused by the kernel rather
 * than corrupt memory. */
#if defined(__linux__) &&                                                                        \
    (defined(__x86_64__) || defined(__i386__) || defined(__aarch64__) || defined(__arm__) ||     \
     defined(__riscv) || defined(__loongarch__))
#define SERIAL_HAVE_TERMIOS2 1
struct mocap_termios2 {
    uint32_t c_iflag;
    uint32_t c_oflag;
    uint32_t c_cflag;
    uint32_t c_lflag;
    unsigned char c_line;
    unsigned char c_cc[19];
    uint32_t c_ispeed;
    uint32_t c_ospeed;
};
_Static_assert(sizeof(struct mocap_termios2) == 44, "kernel struct termios2 is 44 bytes");
#define MOCAP_TCGETS2 _IOR('T', 0x2A, struct mocap_termios2)
#define MOCAP_TCSETS2 _IOW('T', 0x2B, struct mocap_termios2)
#define MOCAP_CBAUD 0x0000100fu
#define MOCAP_BOTHER 0x00001000u
#define MOCAP_IBSHIFT 16
#endif

typedef struct serial_port {
    transport base; /* first: the transport pointer is the serial_port pointer */
    int fd;         /* -1 while disconnected */
    uint32_t baud;
    char path[MOCAP_PATH_MAX];
} serial_port;

static const char *errno_text(int err)
{
    static _Thread_local char text[128];
    return mocap_errno_text(err, text, sizeof text);
}

/* Returns 1 and the speed code when the OS has a named constant (or, on BSD and macOS, when
 * speed_t is the rate itself and cfsetspeed takes any value). */
static int standard_speed(uint32_t baud, speed_t *code)
{
#if defined(__FreeBSD__) || defined(__NetBSD__) || defined(__OpenBSD__) || defined(__DragonFly__)
    *code = (speed_t)baud;
    return 1;
#else
    static const struct {
        uint32_t baud;
        speed_t code;
    } table[] = {
        {50, B50}, {75, B75}, {110, B110}, {134, B134}, {150, B150}, {200, B200}, {300, B300},
        {600, B600}, {1200, B1200}, {1800, B1800}, {2400, B2400}, {4800, B4800},
        {9600, B9600}, {19200, B19200}, {38400, B38400},
#ifdef B57600
        {57600, B57600},
#endif
#ifdef B115200
        {115200, B115200},
#endif
#ifdef B230400
        {230400, B230400},
#endif
#ifdef B460800
        {460800, B460800},
#endif
#ifdef B500000
        {500000, B500000},
#endif
#ifdef B576000
        {576000, B576000},
#endif
#ifdef B921600
        {921600, B921600},
#endif
#ifdef B1000000
        {1000000, B1000000},
#endif
#ifdef B1152000
        {1152000, B1152000},
#endif
#ifdef B1500000
        {1500000, B1500000},
#endif
#ifdef B2000000
        {2000000, B2000000},
#endif
#ifdef B2500000
        {2500000, B2500000},
#endif
#ifdef B3000000
        {3000000, B3000000},
#endif
#ifdef B3500000
        {3500000, B3500000},
#endif
#ifdef B4000000
        {4000000, B4000000},
#endif
    };
    for (size_t i = 0; i < sizeof table / sizeof table[0]; ++i) {
        if (table[i].baud == baud) {
            *code = table[i].code;
            return 1;
        }
    }
    return 0;
#endif
}

/* cfmakeraw() spelled out (it is not POSIX): 8 data bits, no parity, one stop bit, no
 * translation of any byte, no echo, no signals, no software or hardware flow control. */
static void make_raw(struct termios *tio)
{
    tio->c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON |
                                IXOFF | IXANY | INPCK);
#ifdef IUCLC
    tio->c_iflag &= ~(tcflag_t)IUCLC;
#endif
#ifdef IMAXBEL
    tio->c_iflag &= ~(tcflag_t)IMAXBEL;
#endif
    tio->c_oflag &= ~(tcflag_t)OPOST;
    tio->c_lflag &= ~(tcflag_t)(ECHO | ECHOE | ECHOK | ECHONL | ICANON | ISIG | IEXTEN | NOFLSH |
                                TOSTOP);
    tio->c_cflag &= ~(tcflag_t)(CSIZE | PARENB | PARODD | CSTOPB | HUPCL);
#ifdef CRTSCTS
    tio->c_cflag &= ~(tcflag_t)CRTSCTS;
#endif
#ifdef CMSPAR
    tio->c_cflag &= ~(tcflag_t)CMSPAR;
#endif
    tio->c_cflag |= CS8 | CREAD | CLOCAL;
    /* VMIN 1 rather than 0: on Linux a non-blocking read with VMIN 0 / VTIME 0 returns 0 when no
     * byte is queued, which would be indistinguishable from a hangup. With VMIN 1 an empty read
     * is EAGAIN and 0 means the line was hung up. poll() does the waiting. */
    tio->c_cc[VMIN] = 1;
    tio->c_cc[VTIME] = 0;
}

static mocap_status not_a_serial_port(const char *path, const char *what)
{
    return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "%s is not a serial port (%s)", path, what);
}

static mocap_status unsupported_baud(const char *path, uint32_t baud, const char *cause)
{
    return mocap_fail(MOCAP_ERR_UNSUPPORTED, "serial port %s: baud rate %u is not supported (%s)",
                      path, (unsigned)baud, cause);
}

static mocap_status set_custom_speed(int fd, const char *path, uint32_t baud)
{
#if defined(SERIAL_HAVE_TERMIOS2)
    struct mocap_termios2 t2;
    memset(&t2, 0, sizeof t2);
    if (ioctl(fd, MOCAP_TCGETS2, &t2) != 0)
        return unsupported_baud(path, baud, "the kernel has no termios2 support");
    t2.c_cflag &= ~(MOCAP_CBAUD | (MOCAP_CBAUD << MOCAP_IBSHIFT)); /* input speed = output */
    t2.c_cflag |= MOCAP_BOTHER;
    t2.c_ispeed = baud;
    t2.c_ospeed = baud;
    if (ioctl(fd, MOCAP_TCSETS2, &t2) != 0) {
        int err = errno;
        if (err == EINVAL || err == ENOTTY) return unsupported_baud(path, baud, errno_text(err));
        return mocap_fail(MOCAP_ERR_IO, "serial port %s: cannot set baud rate %u: %s", path,
                          (unsigned)baud, errno_text(err));
    }
    /* Drivers round to what their clock divider can do and write back the actual rate; more
     * than 2% off would garble every frame. */
    struct mocap_termios2 check;
    memset(&check, 0, sizeof check);
    if (ioctl(fd, MOCAP_TCGETS2, &check) == 0) {
        uint32_t actual = check.c_ospeed;
        uint32_t diff = actual > baud ? actual - baud : baud - actual;
        if (actual == 0 || diff > baud / 50) {
            char cause[96];
            snprintf(cause, sizeof cause, "the driver set %u instead", (unsigned)actual);
            return unsupported_baud(path, baud, cause);
        }
    }
    return MOCAP_OK;
#elif defined(__APPLE__)
    speed_t speed = (speed_t)baud;
    if (ioctl(fd, IOSSIOSPEED, &speed) != 0) return unsupported_baud(path, baud, errno_text(errno));
    return MOCAP_OK;
#else
    (void)fd;
    return unsupported_baud(path, baud, "no standard constant and no custom-rate support on this OS");
#endif
}

static mocap_status configure(int fd, const char *path, uint32_t baud)
{
    struct termios tio;
    if (tcgetattr(fd, &tio) != 0) {
        int err = errno;
        if (err == ENOTTY || err == EINVAL) return not_a_serial_port(path, "not a terminal device");
        return mocap_fail(MOCAP_ERR_IO, "serial port %s: cannot read settings: %s", path,
                          errno_text(err));
    }
    make_raw(&tio);
    speed_t code;
    int standard = standard_speed(baud, &code);
    if (standard && (cfsetispeed(&tio, code) != 0 || cfsetospeed(&tio, code) != 0))
        return unsupported_baud(path, baud, "rejected by cfsetspeed");
    if (tcsetattr(fd, TCSANOW, &tio) != 0) {
        int err = errno;
        if (err == EINVAL) return unsupported_baud(path, baud, errno_text(err));
        return mocap_fail(MOCAP_ERR_IO, "serial port %s: cannot apply settings: %s", path,
                          errno_text(err));
    }
    if (!standard) return set_custom_speed(fd, path, baud);
    /* tcsetattr succeeds when any part of the request was applied; check the rate stuck. */
    struct termios check;
    if (tcgetattr(fd, &check) == 0 && cfgetospeed(&check) != code)
        return unsupported_baud(path, baud, "the driver refused it");
    return MOCAP_OK;
}

static mocap_status open_error(const char *path, int err)
{
    switch (err) {
    case ENOENT:
    case ENOTDIR:
        return mocap_fail(MOCAP_ERR_NOT_FOUND,
                          "serial port %s not found (is the receiver plugged in?)", path);
    case ENXIO:
    case ENODEV:
        return mocap_fail(MOCAP_ERR_NOT_FOUND, "serial port %s has no device behind it: %s", path,
                          errno_text(err));
    case EACCES:
    case EPERM:
#if defined(__linux__)
        return mocap_fail(MOCAP_ERR_PERMISSION,
                          "permission denied opening serial port %s: add your user to the dialout "
                          "group (sudo usermod -aG dialout $USER, then log in again)",
                          path);
#else
        return mocap_fail(MOCAP_ERR_PERMISSION,
                          "permission denied opening serial port %s: check the device's owner and "
                          "mode",
                          path);
#endif
    case EBUSY:
        return mocap_fail(MOCAP_ERR_IO,
                          "serial port %s is busy: another program has it open exclusively", path);
    case EISDIR:
        return not_a_serial_port(path, "a directory");
    default:
        return mocap_fail(MOCAP_ERR_IO, "cannot open serial port %s: %s", path, errno_text(err));
    }
}

/* Opens and configures path; on success *out_fd is a raw, non-blocking, exclusively held fd. */
static mocap_status open_port(const char *path, uint32_t baud, int *out_fd)
{
    *out_fd = -1;
    /* stat first so a regular file is reported as such instead of being opened read-write. */
    struct stat st;
    if (stat(path, &st) != 0) return open_error(path, errno);
    if (S_ISDIR(st.st_mode)) return not_a_serial_port(path, "a directory");
    if (!S_ISCHR(st.st_mode)) return not_a_serial_port(path, "not a character device");

    int fd;
    do {
        fd = open(path, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    if (fd < 0) return open_error(path, errno);

    /* Two readers on one port would each get half of the byte stream. TIOCEXCL stops other
     * unprivileged opens; flock also catches opens by root and by this process. */
#ifdef TIOCEXCL
    (void)ioctl(fd, TIOCEXCL);
#endif
    if (flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK) {
        close(fd);
        return mocap_fail(MOCAP_ERR_IO, "serial port %s is busy: it is already open (in this or "
                          "another program)", path);
    }

    mocap_status status = configure(fd, path, baud);
    if (status != MOCAP_OK) {
        close(fd);
        return status;
    }
    /* Bytes queued before this open are stale: their receive time would be wrong. */
    (void)tcflush(fd, TCIOFLUSH);
    *out_fd = fd;
    return MOCAP_OK;
}

static mocap_status disconnected(serial_port *port, const char *cause)
{
    if (port->fd >= 0) {
        close(port->fd);
        port->fd = -1;
    }
    return mocap_fail(MOCAP_ERR_DISCONNECTED, "serial port %s disconnected (%s)", port->path, cause);
}

static int is_disconnect_errno(int err)
{
    return err == EIO || err == ENXIO || err == ENODEV || err == EBADF;
}

static mocap_status serial_read(transport *t, uint8_t *buf, size_t cap, int timeout_ms,
                                size_t *got, int64_t *receive_ns)
{
    serial_port *port = (serial_port *)t;
    if (got) *got = 0;
    if (!buf || !got || cap == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port %s: invalid read arguments",
                          port->path);
    if (port->fd < 0)
        return mocap_fail(MOCAP_ERR_DISCONNECTED,
                          "serial port %s is disconnected (reopen it after replugging)", port->path);
    if (timeout_ms < 0) timeout_ms = 0;
    const int64_t deadline = mocap_monotonic_ns() + (int64_t)timeout_ms * 1000000LL;

    for (;;) {
        int64_t left_ns = deadline - mocap_monotonic_ns();
        int wait_ms = left_ns <= 0 ? 0 : (int)((left_ns + 999999) / 1000000);
        struct pollfd pfd = {port->fd, POLLIN, 0};
        int ready = poll(&pfd, 1, wait_ms);
        if (ready < 0) {
            if (errno == EINTR) continue;
            return mocap_fail(MOCAP_ERR_IO, "serial port %s: poll failed: %s", port->path,
                              errno_text(errno));
        }
        if (ready == 0) {
            if (mocap_monotonic_ns() < deadline) continue; /* poll rounds down on some kernels */
            return mocap_fail(MOCAP_ERR_TIMEOUT, "serial port %s: no data within %d ms",
                              port->path, timeout_ms);
        }
        if (pfd.revents & POLLNVAL) {
            /* The fd is not open any more; closing the number could hit someone else's file. */
            port->fd = -1;
            return mocap_fail(MOCAP_ERR_DISCONNECTED, "serial port %s: handle became invalid",
                              port->path);
        }
        /* Read before honouring a hangup so bytes that arrived just before the unplug are kept. */
        if (pfd.revents & POLLIN) {
            size_t want = cap > (size_t)SSIZE_MAX ? (size_t)SSIZE_MAX : cap;
            ssize_t n = read(port->fd, buf, want);
            if (n > 0) {
                *got = (size_t)n;
                if (receive_ns) *receive_ns = mocap_monotonic_ns();
                return MOCAP_OK;
            }
            if (n == 0) return disconnected(port, "end of file: the line was hung up");
            int err = errno;
            if (err == EINTR || err == EAGAIN || err == EWOULDBLOCK) {
                if (!(pfd.revents & (POLLHUP | POLLERR))) {
                    /* A readiness report that keeps producing nothing must not spin forever. */
                    if (mocap_monotonic_ns() >= deadline)
                        return mocap_fail(MOCAP_ERR_TIMEOUT, "serial port %s: no data within %d ms",
                                          port->path, timeout_ms);
                    continue;
                }
            } else if (is_disconnect_errno(err)) {
                return disconnected(port, errno_text(err));
            } else {
                return mocap_fail(MOCAP_ERR_IO, "serial port %s: read failed: %s", port->path,
                                  errno_text(err));
            }
        }
        if (pfd.revents & POLLHUP) return disconnected(port, "hangup");
        if (pfd.revents & POLLERR) return disconnected(port, "device error");
    }
}

static mocap_status serial_reopen(transport *t)
{
    serial_port *port = (serial_port *)t;
    if (port->fd >= 0) {
        close(port->fd);
        port->fd = -1;
    }
    return open_port(port->path, port->baud, &port->fd);
}

static void serial_close(transport *t)
{
    serial_port *port = (serial_port *)t;
    if (port->fd >= 0) close(port->fd);
    free(port);
}

static const transport_ops serial_ops = {serial_read, serial_reopen, serial_close, NULL};

mocap_status transport_open_serial(const char *path, uint32_t baud, transport **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port: NULL output pointer");
    *out = NULL;
    if (!path || !path[0])
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port: no port path given");
    if (strlen(path) >= MOCAP_PATH_MAX)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port path is too long (%zu bytes)",
                          strlen(path));
    if (baud == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "serial port %s: baud rate 0 is invalid",
                          path);

    serial_port *port = (serial_port *)calloc(1, sizeof *port);
    if (!port) return mocap_fail(MOCAP_ERR_NO_MEMORY, "serial port %s: out of memory", path);
    port->base.ops = &serial_ops;
    port->baud = baud;
    snprintf(port->path, sizeof port->path, "%s", path);
    snprintf(port->base.description, sizeof port->base.description, "serial port %s", path);

    mocap_status status = open_port(path, baud, &port->fd);
    if (status != MOCAP_OK) {
        free(port);
        return status;
    }
    *out = &port->base;
    return MOCAP_OK;
}
