/* Connection-less UDP sender (see udp_sender.h). */
#if !defined(_WIN32) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L
#endif
#include "udp_sender.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"

#if defined(_WIN32)
#include <winsock2.h>
#include <ws2tcpip.h>
typedef SOCKET udp_socket;
#define UDP_INVALID INVALID_SOCKET
#define udp_close_socket closesocket
static int last_socket_error(void) { return WSAGetLastError(); }
#else
#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <unistd.h>
typedef int udp_socket;
#define UDP_INVALID (-1)
#define udp_close_socket close
static int last_socket_error(void) { return errno; }
#endif

struct udp_sender {
    udp_socket sock;
    struct sockaddr_storage addr;
    int addr_len;
    int loopback;
    char given[256];   /* the destination as the caller wrote it */
    char address[80];  /* numeric address:port */
};

static const char *socket_error_text(int err, char *buf, size_t cap)
{
#if defined(_WIN32)
    buf[0] = '\0';
    FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, NULL, (DWORD)err, 0,
                   buf, (DWORD)cap, NULL);
    size_t n = strlen(buf);
    while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == '\r' || buf[n - 1] == '.')) buf[--n] = '\0';
    if (n == 0) snprintf(buf, cap, "socket error %d", err);
    return buf;
#else
    return mocap_errno_text(err, buf, cap);
#endif
}

#if defined(_WIN32)
/* Winsock is started once per process (WSAStartup counts its own references). InitOnce makes
 * a second thread wait until the first one's WSAStartup has finished; a failed start is retried
 * by the next call. */
static BOOL CALLBACK start_winsock(PINIT_ONCE once, PVOID param, PVOID *context)
{
    (void)once;
    (void)param;
    (void)context;
    WSADATA data;
    return WSAStartup(MAKEWORD(2, 2), &data) == 0;
}

static int winsock_up(void)
{
    static INIT_ONCE once = INIT_ONCE_STATIC_INIT;
    return InitOnceExecuteOnce(&once, start_winsock, NULL, NULL) ? 0 : -1;
}
#endif

mocap_status udp_parse_destination(const char *destination, int default_port, char *host,
                                   size_t host_cap, int *port)
{
    const char *d = (destination && destination[0]) ? destination : UDP_DEFAULT_DESTINATION;
    const char *shown = d;
    const char *port_text = NULL;
    size_t host_len;
    if (d[0] == '[') {
        const char *close = strchr(d, ']');
        if (!close) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "destination '%s': missing ']'", shown);
        host_len = (size_t)(close - d - 1);
        d += 1;
        if (close[1] == ':') port_text = close + 2;
        else if (close[1] != '\0')
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "destination '%s': expected ':PORT' after ']'", shown);
    } else {
        const char *colon = strchr(d, ':');
        if (colon && strchr(colon + 1, ':')) {
            host_len = strlen(d); /* a bare IPv6 address: no port */
        } else if (colon) {
            host_len = (size_t)(colon - d);
            port_text = colon + 1;
        } else {
            host_len = strlen(d);
        }
    }
    if (host_len == 0)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "destination '%s': no host (use HOST:PORT, e.g. "
                          "127.0.0.1:39539)", shown);
    if (host_len >= host_cap)
        return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "destination '%s': host name too long", shown);
    memcpy(host, d, host_len);
    host[host_len] = '\0';
    *port = default_port;
    if (port_text) {
        char *end = NULL;
        long p = strtol(port_text, &end, 10);
        if (!port_text[0] || *end != '\0' || p < 1 || p > 65535)
            return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT,
                              "destination '%s': port must be a number from 1 to 65535", shown);
        *port = (int)p;
    }
    return MOCAP_OK;
}

static int is_loopback(const struct sockaddr *sa)
{
    if (sa->sa_family == AF_INET) {
        const struct sockaddr_in *in = (const struct sockaddr_in *)sa;
        return (ntohl(in->sin_addr.s_addr) >> 24) == 127;
    }
    if (sa->sa_family == AF_INET6) {
        const struct sockaddr_in6 *in6 = (const struct sockaddr_in6 *)sa;
        static const unsigned char loop6[16] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1};
        static const unsigned char mapped[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff};
        const unsigned char *a = (const unsigned char *)&in6->sin6_addr;
        if (memcmp(a, loop6, 16) == 0) return 1;
        return memcmp(a, mapped, 12) == 0 && a[12] == 127;
    }
    return 0;
}

mocap_status udp_sender_open(const char *destination, int allow_remote, udp_sender **out)
{
    if (!out) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "udp_sender_open: out is NULL");
    *out = NULL;
    const char *given = (destination && destination[0]) ? destination : UDP_DEFAULT_DESTINATION;
    char host[200];
    int port = 0;
    mocap_status st = udp_parse_destination(given, UDP_DEFAULT_PORT, host, sizeof host, &port);
    if (st != MOCAP_OK) return st;
#if defined(_WIN32)
    if (winsock_up() != 0)
        return mocap_fail(MOCAP_ERR_IO, "destination '%s': Winsock did not start", given);
#endif
    char port_text[16];
    snprintf(port_text, sizeof port_text, "%d", port);
    struct addrinfo hints, *res = NULL;
    memset(&hints, 0, sizeof hints);
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_DGRAM;
    hints.ai_protocol = IPPROTO_UDP;
    hints.ai_flags = AI_NUMERICSERV;
    int gai = getaddrinfo(host, port_text, &hints, &res);
    if (gai != 0 || !res) {
#if defined(_WIN32)
        const char *why = "host not found";
#else
        const char *why = gai_strerror(gai);
#endif
        if (res) freeaddrinfo(res);
        return mocap_fail(MOCAP_ERR_NOT_FOUND, "destination '%s': cannot resolve '%s': %s", given,
                          host, why);
    }
    udp_sender *s = (udp_sender *)calloc(1, sizeof *s);
    if (!s) {
        freeaddrinfo(res);
        return mocap_fail(MOCAP_ERR_NO_MEMORY, "destination '%s': out of memory", given);
    }
    s->sock = UDP_INVALID;
    snprintf(s->given, sizeof s->given, "%s", given);
    struct addrinfo *ai = res;
    while (ai && ai->ai_family != AF_INET && ai->ai_family != AF_INET6) ai = ai->ai_next;
    if (!ai || ai->ai_addrlen > sizeof s->addr) {
        freeaddrinfo(res);
        free(s);
        return mocap_fail(MOCAP_ERR_NOT_FOUND, "destination '%s': no IPv4 or IPv6 address", given);
    }
    memcpy(&s->addr, ai->ai_addr, ai->ai_addrlen);
    s->addr_len = (int)ai->ai_addrlen;
    freeaddrinfo(res);
    s->loopback = is_loopback((const struct sockaddr *)&s->addr);

    char numeric[64] = "?";
    if (s->addr.ss_family == AF_INET)
        inet_ntop(AF_INET, &((struct sockaddr_in *)&s->addr)->sin_addr, numeric, sizeof numeric);
    else
        inet_ntop(AF_INET6, &((struct sockaddr_in6 *)&s->addr)->sin6_addr, numeric, sizeof numeric);
    snprintf(s->address, sizeof s->address, s->addr.ss_family == AF_INET6 ? "[%s]:%d" : "%s:%d",
             numeric, port);

    if (!s->loopback && !allow_remote) {
        mocap_status r = mocap_fail(MOCAP_ERR_PERMISSION,
                                    "destination '%s' (%s) is not on this machine: sending poses "
                                    "over the network must be asked for explicitly (allow_remote, "
                                    "mocapctl --allow-remote)", given, s->address);
        free(s);
        return r;
    }

    char err[160];
#if defined(SOCK_CLOEXEC)
    /* Not inherited by programs the host starts (the Unity editor runs tools). */
    s->sock = socket(s->addr.ss_family, SOCK_DGRAM | SOCK_CLOEXEC, IPPROTO_UDP);
#else
    s->sock = socket(s->addr.ss_family, SOCK_DGRAM, IPPROTO_UDP);
#endif
    if (s->sock == UDP_INVALID) {
        int e = last_socket_error();
        free(s);
        return mocap_fail(MOCAP_ERR_IO, "destination '%s': cannot create a UDP socket: %s", given,
                          socket_error_text(e, err, sizeof err));
    }
    if (s->loopback) {
        /* Our own end on loopback too: the sending port is not reachable from the network. */
        struct sockaddr_storage local;
        memset(&local, 0, sizeof local);
        int local_len;
        if (s->addr.ss_family == AF_INET) {
            struct sockaddr_in *l = (struct sockaddr_in *)&local;
            l->sin_family = AF_INET;
            l->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
            local_len = (int)sizeof *l;
        } else {
            struct sockaddr_in6 *l = (struct sockaddr_in6 *)&local;
            l->sin6_family = AF_INET6;
            l->sin6_addr = in6addr_loopback;
            local_len = (int)sizeof *l;
        }
        if (bind(s->sock, (struct sockaddr *)&local, local_len) != 0) {
            int e = last_socket_error();
            udp_close_socket(s->sock);
            free(s);
            return mocap_fail(MOCAP_ERR_IO, "destination '%s': cannot bind to loopback: %s", given,
                              socket_error_text(e, err, sizeof err));
        }
    }
    *out = s;
    return MOCAP_OK;
}

mocap_status udp_sender_send(udp_sender *s, const void *data, size_t size)
{
    if (!s || (!data && size)) return mocap_fail(MOCAP_ERR_INVALID_ARGUMENT, "udp_sender_send: NULL");
#if defined(_WIN32)
    int n = sendto(s->sock, (const char *)data, (int)size, 0, (const struct sockaddr *)&s->addr,
                   s->addr_len);
    if (n == SOCKET_ERROR || (size_t)n != size) {
#else
    ssize_t n;
    do {
        n = sendto(s->sock, data, size, 0, (const struct sockaddr *)&s->addr, (socklen_t)s->addr_len);
    } while (n < 0 && errno == EINTR);
    if (n < 0 || (size_t)n != size) {
#endif
        char err[160];
        int e = last_socket_error();
        return mocap_fail(MOCAP_ERR_IO, "sending %zu bytes to '%s' (%s): %s", size, s->given,
                          s->address, n < 0 ? socket_error_text(e, err, sizeof err) : "short send");
    }
    return MOCAP_OK;
}

void udp_sender_close(udp_sender *s)
{
    if (!s) return;
    if (s->sock != UDP_INVALID) udp_close_socket(s->sock);
    free(s);
}

const char *udp_sender_address(const udp_sender *s) { return s ? s->address : ""; }
int udp_sender_is_loopback(const udp_sender *s) { return s ? s->loopback : 0; }
