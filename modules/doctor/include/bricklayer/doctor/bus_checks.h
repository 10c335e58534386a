// The bus on this host: the URL, the multicast route the kernel would use for it, whether a message
// sent on it comes back to this host (loopback), and the receive buffers LAN use needs.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

struct UdpmUrl {
  std::string group = "239.255.76.67";
  int port = 7667;
  int ttl = 0;
  std::optional<int64_t> recv_buf_size;
};
// nullopt for a provider other than udpm; throws std::invalid_argument for a udpm URL LCM would refuse.
std::optional<UdpmUrl> parse_udpm_url(const std::string& url);

// The recommended kernel cap and request for LAN use (modules/launcher/README.md).
inline constexpr int64_t kLanReceiveBuffer = 8 << 20;

CheckResult check_bus_url(const HostPlan& plan);
// Asks the kernel which route and interface a datagram to the group would take (connect on a UDP
// socket), and whether that interface is up and multicast-capable.
CheckResult check_multicast_route(const HostPlan& plan);
// Publishes a message on the URL and waits up to timeout_s for it to come back on this host.
CheckResult check_bus_loopback(const HostPlan& plan, double timeout_s);
// net.core.rmem_max against what the URL asks for (or kLanReceiveBuffer on a LAN), and what the
// kernel actually grants a socket that asks.
CheckResult check_receive_buffers(const HostPlan& plan, const std::string& rmem_max_path = "/proc/sys/net/core/rmem_max");

}  // namespace bricklayer::doctor
