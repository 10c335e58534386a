// Which LCM URL a process uses, and what it means for who can hear it.
#pragma once

#include <string>

namespace bricklayer {

// Host-only multicast: ttl=0 keeps every packet on this machine (the default; see README "Security").
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

// --lcm-url if given, else LCM_DEFAULT_URL from the environment, else kDefaultLcmUrl.
std::string resolve_lcm_url(const std::string& flag_value);

// Throws std::invalid_argument with a fixable message for URLs LCM would reject or that are unsafe by
// accident: unknown provider, ttl above 1 (routed beyond the LAN) unless allow_routed is set.
void check_lcm_url(const std::string& url, bool allow_routed = false);

}  // namespace bricklayer
