#include "bricklayer/logger/udp_socket_stats.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

namespace bricklayer::logger {
namespace {

// Calls visit(fd, inode) for each of this process's UDP sockets bound to port.
void for_each_socket(int port, const std::function<void(int, unsigned long)>& visit) {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    std::error_code lec;
    const std::string target = std::filesystem::read_symlink(entry.path(), lec).string();
    if (lec || target.rfind("socket:[", 0) != 0) continue;
    const int fd = std::atoi(entry.path().filename().c_str());
    int type = 0;
    socklen_t len = sizeof type;
    if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_DGRAM) continue;
    sockaddr_storage addr{};
    socklen_t alen = sizeof addr;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &alen) != 0) continue;
    int bound = -1;
    if (addr.ss_family == AF_INET) bound = ntohs(reinterpret_cast<sockaddr_in*>(&addr)->sin_port);
    if (addr.ss_family == AF_INET6) bound = ntohs(reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port);
    if (bound != port) continue;
    visit(fd, std::stoul(target.substr(8)));
  }
}

// "drops" (the last column) of the /proc/net/udp{,6} rows of these inodes.
int64_t kernel_drops(const std::set<unsigned long>& inodes) {
  int64_t drops = 0;
  for (const char* table : {"/proc/net/udp", "/proc/net/udp6"}) {
    std::ifstream in(table);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string f[13];
      int n = 0;
      while (n < 13 && fields >> f[n]) ++n;
      if (n < 13) continue;
      if (inodes.count(std::stoul(f[9]))) drops += std::stoll(f[12]);
    }
  }
  return drops;
}

}  // namespace

int udpm_port(const std::string& url) {
  if (url.rfind("udpm://", 0) != 0) return -1;
  const std::string address = url.substr(7, url.find('?') == std::string::npos ? std::string::npos : url.find('?') - 7);
  const size_t colon = address.rfind(':');
  if (colon == std::string::npos) return 7667;
  try {
    return std::stoi(address.substr(colon + 1));
  } catch (const std::exception&) {
    return -1;
  }
}

UdpSocketStats udp_socket_stats(int port) {
  UdpSocketStats stats;
  std::set<unsigned long> inodes;
  int64_t smallest = LLONG_MAX;
  for_each_socket(port, [&](int fd, unsigned long inode) {
    ++stats.sockets;
    inodes.insert(inode);
    int size = 0;
    socklen_t len = sizeof size;
    if (getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &size, &len) == 0 && size < smallest) smallest = size;
  });
  stats.rcvbuf_bytes = smallest == LLONG_MAX ? 0 : smallest;
  stats.drops = kernel_drops(inodes);
  return stats;
}

UdpSocketStats raise_receive_buffer(int port, int64_t bytes) {
  const int request = static_cast<int>(std::min<int64_t>(bytes, INT_MAX / 2));
  for_each_socket(port, [&](int fd, unsigned long) {
    if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &request, sizeof request) != 0)
      setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &request, sizeof request);
  });
  return udp_socket_stats(port);
}

}  // namespace bricklayer::logger
