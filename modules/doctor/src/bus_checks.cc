#include "bricklayer/doctor/bus_checks.h"

#include <arpa/inet.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>


#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "bricklayer/common/lcm_url.h"
#include "bricklayer/doctor/quiet_stderr.h"
#include "bricklayer/runtime/lcm_bus.h"

namespace bricklayer::doctor {
namespace {

std::string mb(int64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f MB", bytes / 1048576.0);
  return text;
}

struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

// The interface the kernel routes a datagram to `group` through, as the routing table answers an
// RTM_GETROUTE request (what `ip route get` asks): its name and flags. A UDP socket's source address
// cannot tell (a route on lo without a source address leaves from 0.0.0.0).
std::optional<std::pair<std::string, unsigned>> route_interface(in_addr group) {
  Fd nl{socket(AF_NETLINK, SOCK_RAW | SOCK_CLOEXEC, NETLINK_ROUTE)};
  if (nl.fd < 0) return std::nullopt;
  struct {
    nlmsghdr header;
    rtmsg route;
    char attributes[64];
  } request{};
  request.header.nlmsg_len = NLMSG_LENGTH(sizeof(rtmsg));
  request.header.nlmsg_type = RTM_GETROUTE;
  request.header.nlmsg_flags = NLM_F_REQUEST;
  request.header.nlmsg_seq = 1;
  request.route.rtm_family = AF_INET;
  request.route.rtm_dst_len = 32;
  auto* dst = reinterpret_cast<rtattr*>(reinterpret_cast<char*>(&request) + NLMSG_ALIGN(request.header.nlmsg_len));
  dst->rta_type = RTA_DST;
  dst->rta_len = RTA_LENGTH(sizeof(group));
  std::memcpy(RTA_DATA(dst), &group, sizeof(group));
  request.header.nlmsg_len = NLMSG_ALIGN(request.header.nlmsg_len) + RTA_ALIGN(dst->rta_len);
  if (send(nl.fd, &request, request.header.nlmsg_len, 0) < 0) return std::nullopt;
  char reply[8192];
  ssize_t n = recv(nl.fd, reply, sizeof(reply), 0);
  if (n <= 0) return std::nullopt;
  for (auto* h = reinterpret_cast<nlmsghdr*>(reply); NLMSG_OK(h, static_cast<unsigned>(n)); h = NLMSG_NEXT(h, n)) {
    if (h->nlmsg_type != RTM_NEWROUTE) continue;
    auto* rt = static_cast<rtmsg*>(NLMSG_DATA(h));
    int length = static_cast<int>(RTM_PAYLOAD(h));
    for (auto* a = RTM_RTA(rt); RTA_OK(a, length); a = RTA_NEXT(a, length)) {
      if (a->rta_type != RTA_OIF) continue;
      const int index = *static_cast<int*>(RTA_DATA(a));
      char name[IF_NAMESIZE] = {};
      if (!if_indextoname(static_cast<unsigned>(index), name)) return std::nullopt;
      ifreq ifr{};
      std::memcpy(ifr.ifr_name, name, strnlen(name, IF_NAMESIZE - 1));
      Fd s{socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0)};
      if (s.fd < 0 || ioctl(s.fd, SIOCGIFFLAGS, &ifr) != 0) return std::nullopt;
      return std::make_pair(std::string(name), static_cast<unsigned>(static_cast<unsigned short>(ifr.ifr_flags)));
    }
  }
  return std::nullopt;
}

const std::string kLanUrl = "udpm://239.255.76.67:7667?ttl=1";

}  // namespace

std::optional<UdpmUrl> parse_udpm_url(const std::string& url) {
  check_lcm_url(url);
  if (url.rfind("udpm://", 0) != 0) return std::nullopt;
  UdpmUrl out;
  std::string rest = url.substr(7);
  std::string options;
  if (auto q = rest.find('?'); q != std::string::npos) {
    options = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  if (!rest.empty()) {
    auto colon = rest.find(':');
    out.group = rest.substr(0, colon);
    if (colon != std::string::npos) out.port = std::atoi(rest.c_str() + colon + 1);
  }
  in_addr a{};
  if (inet_pton(AF_INET, out.group.c_str(), &a) != 1 || (ntohl(a.s_addr) >> 28) != 0xE)
    throw std::invalid_argument("LCM URL '" + url + "': '" + out.group + "' is not a multicast address (224.0.0.0/4)");
  if (out.port <= 0 || out.port > 65535) throw std::invalid_argument("LCM URL '" + url + "': bad port");
  // Options in order; LCM keeps the last of a repeated one.
  size_t start = 0;
  while (start <= options.size() && !options.empty()) {
    size_t end = options.find('&', start);
    std::string kv = options.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (kv.rfind("ttl=", 0) == 0) out.ttl = std::atoi(kv.c_str() + 4);
    if (kv.rfind("recv_buf_size=", 0) == 0) out.recv_buf_size = std::atoll(kv.c_str() + 14);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

CheckResult check_bus_url(const HostPlan& plan) {
  const std::string name = "bus url";
  std::optional<UdpmUrl> u;
  try {
    u = parse_udpm_url(plan.lcm_url);
  } catch (const std::invalid_argument& e) {
    return CheckResult::failed(name, e.what(), "use --lcm-url '" + std::string(kDefaultLcmUrl) + "' (one host) or '" + kLanUrl + "' (LAN)");
  }
  if (!u) return CheckResult::warning(name, plan.lcm_url + " is not multicast: other processes cannot join it", "use a udpm:// URL");
  if (plan.two_hosts && u->ttl == 0)
    return CheckResult::failed(name, plan.lcm_url + ": ttl=0 never leaves this host, but profile " + plan.profile +
                                         " needs the other host",
                               "--lcm-url '" + kLanUrl + "' on both hosts");
  return CheckResult::ok(name, plan.lcm_url + (u->ttl == 0 ? " (this host only)" : " (the local network, ttl=1)"));
}

CheckResult check_multicast_route(const HostPlan& plan) {
  const std::string name = "multicast route";
  std::optional<UdpmUrl> u;
  try {
    u = parse_udpm_url(plan.lcm_url);
  } catch (const std::invalid_argument& e) {
    return CheckResult::failed(name, e.what(), "see 'bus url'");
  }
  if (!u) return CheckResult::ok(name, "not a multicast URL: no route needed");
  const std::string dev_hint = u->ttl == 0 ? "lo" : "eth0 (the interface facing the other host)";
  const std::string add_route = "sudo ip route add 224.0.0.0/4 dev " + dev_hint;
  Fd s{socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0)};
  if (s.fd < 0) return CheckResult::failed(name, std::string("cannot open a UDP socket: ") + std::strerror(errno), "");
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<uint16_t>(u->port));
  inet_pton(AF_INET, u->group.c_str(), &to.sin_addr);
  if (connect(s.fd, reinterpret_cast<sockaddr*>(&to), sizeof(to)) != 0)
    return CheckResult::failed(name, "no route to " + u->group + " (" + std::strerror(errno) + "): LCM cannot send", add_route);
  sockaddr_in from{};
  socklen_t len = sizeof(from);
  getsockname(s.fd, reinterpret_cast<sockaddr*>(&from), &len);
  char source[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &from.sin_addr, source, sizeof(source));
  auto iface = route_interface(to.sin_addr);
  if (!iface) return CheckResult::warning(name, "routed, but the routing table names no interface for " + u->group, add_route);
  const auto& [dev, flags] = *iface;
  const std::string where = u->group + " leaves via " + dev + (from.sin_addr.s_addr != 0 ? " (" + std::string(source) + ")" : "");
  if (!(flags & IFF_UP)) return CheckResult::failed(name, where + ", which is down", "sudo ip link set " + dev + " up");
  if (u->ttl >= 1 && (flags & IFF_LOOPBACK))
    return CheckResult::failed(name, where + ": the other host will not hear it", "sudo ip route add 224.0.0.0/4 dev eth0 (the interface facing the other host)");
  // Off on a LAN interface: it joins no group, so the other host's messages never arrive. On lo the
  // kernel still loops messages back (the loopback check below tells).
  if (!(flags & IFF_MULTICAST)) {
    const std::string fix = "sudo ip link set " + dev + " multicast on";
    return u->ttl >= 1 ? CheckResult::failed(name, where + ", which has multicast off", fix)
                       : CheckResult::warning(name, where + ", which has multicast off", fix);
  }
  return CheckResult::ok(name, where);
}

CheckResult check_bus_loopback(const HostPlan& plan, double timeout_s) {
  const std::string name = "bus loopback";
  try {
    check_lcm_url(plan.lcm_url);
  } catch (const std::invalid_argument& e) {
    return CheckResult::failed(name, e.what(), "see 'bus url'");
  }
  QuietStderr quiet;
  runtime::LcmBus bus(plan.lcm_url);
  if (!bus.open()) return CheckResult::failed(name, "LCM cannot open " + plan.lcm_url + ": " + bus.problem(), "see 'multicast route'");
  // A channel of this process alone, so another doctor's check is never taken for ours.
  const std::string channel = "BL_DOCTOR_LOOPBACK_" + std::to_string(getpid());
  bool got = false;
  bus.subscribe(channel, runtime::QueuePolicy::keep(16), [&](const runtime::Received&) { got = true; });
  const auto start = std::chrono::steady_clock::now();
  const auto deadline = start + std::chrono::duration<double>(timeout_s);
  const uint8_t payload[16] = {};
  auto next_send = start;
  bool sent = false;
  while (!got && std::chrono::steady_clock::now() < deadline) {
    if (std::chrono::steady_clock::now() >= next_send) {
      sent = bus.publish(channel, payload, sizeof(payload)) || sent;
      next_send += std::chrono::milliseconds(100);
    }
    bus.handle(20);
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!got)
    return CheckResult::failed(name, std::string(sent ? "a message sent on " : "nothing could be sent on ") + plan.lcm_url +
                                         " (" + (bus.problem().empty() ? "no answer" : bus.problem()) + ") within " +
                                         std::to_string(static_cast<int>(timeout_s * 1000)) + " ms: this host's modules cannot hear each other",
                               "check the multicast route and the firewall (allow UDP to the group's port)");
  char detail[128];
  std::snprintf(detail, sizeof(detail), "a message sent on the bus came back in %.1f ms", ms);
  return CheckResult::ok(name, detail);
}

CheckResult check_receive_buffers(const HostPlan& plan, const std::string& rmem_max_path) {
  const std::string name = "receive buffers";
  std::optional<UdpmUrl> u;
  try {
    u = parse_udpm_url(plan.lcm_url);
  } catch (const std::invalid_argument& e) {
    return CheckResult::failed(name, e.what(), "see 'bus url'");
  }
  if (!u) return CheckResult::ok(name, "not a multicast URL");
  int64_t rmem_max = -1;
  std::ifstream(rmem_max_path) >> rmem_max;
  const std::string rmem = rmem_max >= 0 ? "net.core.rmem_max is " + mb(rmem_max) : "net.core.rmem_max unreadable";
  const int64_t want = u->recv_buf_size.value_or(u->ttl >= 1 ? kLanReceiveBuffer : 0);
  if (want <= 0) return CheckResult::ok(name, rmem + " (one host: the default buffers do)");
  // Ask the kernel as LCM will: SO_RCVBUF is capped silently at rmem_max (getsockopt reports twice the grant).
  int granted = -1;
  {
    Fd s{socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0)};
    int ask = static_cast<int>(std::min<int64_t>(want, 1 << 30));
    socklen_t len = sizeof(granted);
    if (s.fd >= 0 && setsockopt(s.fd, SOL_SOCKET, SO_RCVBUF, &ask, sizeof(ask)) == 0 &&
        getsockopt(s.fd, SOL_SOCKET, SO_RCVBUF, &granted, &len) == 0)
      granted /= 2;
  }
  const std::string value = "net.core.rmem_max=" + std::to_string(std::max<int64_t>(want, kLanReceiveBuffer));
  const std::string sysctl = "sudo sysctl -w " + value + " (permanent: the line " + value + " in /etc/sysctl.d/90-bricklayer.conf)";
  if (granted >= 0 && granted < want)
    return CheckResult::warning(name, rmem + ": a socket asking for " + mb(want) + " gets " + mb(granted) +
                                          "; a camera frame is lost whole when one of its 64 KB pieces is dropped",
                                sysctl);
  if (u->ttl >= 1 && !u->recv_buf_size)
    return CheckResult::warning(name, rmem + ", but the URL asks for no larger buffer",
                                "add &recv_buf_size=" + std::to_string(kLanReceiveBuffer) + " to --lcm-url");
  return CheckResult::ok(name, rmem + "; a socket asking for " + mb(want) + " gets it");
}

}  // namespace bricklayer::doctor
