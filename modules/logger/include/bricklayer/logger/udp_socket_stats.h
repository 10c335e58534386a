// What the kernel knows about this process's bus socket: how many datagrams it dropped because the
// receive buffer was full (/proc/net/udp "drops", the one loss LCM cannot see) and how big that
// buffer really is (the kernel silently caps an SO_RCVBUF request at net.core.rmem_max).
#pragma once

#include <cstdint>
#include <string>

namespace bricklayer::logger {

struct UdpSocketStats {
  int sockets = 0;           // this process's UDP sockets bound to the port
  int64_t drops = 0;         // datagrams the kernel dropped on them (receive buffer full)
  int64_t rcvbuf_bytes = 0;  // smallest SO_RCVBUF among them (the kernel reports twice the request)
};

// The UDP port of an udpm:// URL (LCM's default 7667 when the URL names none); -1 for other providers.
int udpm_port(const std::string& url);

UdpSocketStats udp_socket_stats(int port);

// Asks for a receive buffer of at least `bytes` on this process's sockets bound to port, with
// SO_RCVBUFFORCE (allowed for root: beyond rmem_max) and else SO_RCVBUF. Returns the stats after.
UdpSocketStats raise_receive_buffer(int port, int64_t bytes);

}  // namespace bricklayer::logger
