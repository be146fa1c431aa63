/* Connection-less UDP datagram sender (POSIX sockets; Winsock behind _WIN32).
 *
 * Destination syntax: "host:port", "host" (default port), "[v6addr]:port", "v6addr", "" or NULL
 * (the default, UDP_DEFAULT_DESTINATION). Host names are resolved once at open (getaddrinfo);
 * the first IPv4 or IPv6 address is used. For a loopback destination the socket is bound to the
 * loopback address, so nothing of ours is reachable from another machine; the sender never
 * reads. Sending to a non-loopback address needs allow_remote (the caller asked for it).
 *
 * Errors: mocap_status + mocap_last_error(), always naming the destination as given. */
#ifndef MOCAP_UDP_SENDER_H
#define MOCAP_UDP_SENDER_H

#include <stddef.h>
#include "mocap_imu.h"

#ifdef __cplusplus
extern "C" {
#endif

#define UDP_DEFAULT_HOST "127.0.0.1"
#define UDP_DEFAULT_PORT 39539
#define UDP_DEFAULT_DESTINATION "127.0.0.1:39539"

typedef struct udp_sender udp_sender;

/* Splits a destination into host (without brackets) and port. MOCAP_ERR_INVALID_ARGUMENT for a
 * malformed one (empty host, bad or out-of-range port, unbalanced brackets). */
mocap_status udp_parse_destination(const char *destination, int default_port, char *host,
                                   size_t host_cap, int *port);

mocap_status udp_sender_open(const char *destination, int allow_remote, udp_sender **out);
/* One datagram. MOCAP_ERR_IO naming the destination when the OS refuses it. */
mocap_status udp_sender_send(udp_sender *s, const void *data, size_t size);
void udp_sender_close(udp_sender *s);
/* Numeric "address:port" ("[::1]:port" for IPv6) actually used. */
const char *udp_sender_address(const udp_sender *s);
int udp_sender_is_loopback(const udp_sender *s);

#ifdef __cplusplus
}
#endif
#endif
