#include "bricklayer/common/lcm_url.h"

#include <cstdlib>
#include <stdexcept>

#include "bricklayer/common/channels.h"

namespace bricklayer {

std::string channel(const char* name) {
  const char* prefix = std::getenv("BRICKLAYER_CHANNEL_PREFIX");
  return (prefix ? std::string(prefix) : std::string()) + name;
}

std::string resolve_lcm_url(const std::string& flag_value) {
  if (!flag_value.empty()) return flag_value;
  if (const char* env = std::getenv("LCM_DEFAULT_URL"); env && *env) return env;
  return kDefaultLcmUrl;
}

void check_lcm_url(const std::string& url, bool allow_routed) {
  auto scheme_end = url.find("://");
  if (scheme_end == std::string::npos)
    throw std::invalid_argument("LCM URL '" + url + "' has no provider (expected e.g. " + kDefaultLcmUrl + ")");
  std::string provider = url.substr(0, scheme_end);
  if (provider != "udpm" && provider != "file" && provider != "memq" && provider != "tcpq")
    throw std::invalid_argument("LCM URL '" + url + "': unknown provider '" + provider +
                                "' (expected udpm, file, memq or tcpq)");
  if (provider == "udpm") {
    // Every occurrence: LCM keeps the last value of a repeated option, so "?ttl=0&ttl=5" is ttl=5.
    for (auto ttl = url.find("ttl="); ttl != std::string::npos; ttl = url.find("ttl=", ttl + 4)) {
      int value = std::atoi(url.c_str() + ttl + 4);
      if (value > 1 && !allow_routed)
        throw std::invalid_argument("LCM URL '" + url + "': ttl=" + std::to_string(value) +
                                    " would route the bus beyond the local network; use ttl=0 (this host) or "
                                    "ttl=1 (LAN)");
    }
  }
}

}  // namespace bricklayer
