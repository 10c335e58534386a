// The clock offset to the other host of a two-host exhibit, from heartbeats: each carries the
// sender's wall clock at publication (heartbeat_t.utime); received at our wall clock, the difference
// is our offset plus the network delay, so the smallest difference over a few seconds bounds the
// offset from above with the delay of the fastest heartbeat (well under a millisecond on a LAN).
// No module compares clocks across hosts, so an offset never stops the exhibit; it makes the
// latencies measured across hosts and the order of a log's events wrong.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bricklayer/doctor/check.h"
#include "bricklayer/doctor/host_plan.h"

namespace bricklayer::doctor {

struct HeartbeatSample {
  std::string module;
  std::string instance;    // "host:pid"
  int64_t sent_utime = 0;      // heartbeat_t.utime (the sender's clock)
  int64_t received_utime = 0;  // our clock when it arrived
};

struct PeerOffset {
  std::string host;
  double offset_ms = 0;  // our clock minus the peer's (positive: the peer is behind), delay included
  double spread_ms = 0;  // largest minus smallest difference (delay jitter)
  int samples = 0;
};

// Per other host (instance host != own_host), the smallest received - sent difference.
std::vector<PeerOffset> estimate_offsets(const std::vector<HeartbeatSample>& samples, const std::string& own_host);

inline constexpr double kClockWarningMs = 10;  // the cross-host latency target is 10 ms p99

CheckResult judge_clock(const HostPlan& plan, const std::vector<PeerOffset>& peers, double listened_s);

// Listens on the URL for `seconds`, publishing a heartbeat of our own ("doctor") every second so a
// doctor on the other host measures us too. Throws std::runtime_error when the bus cannot be opened.
std::vector<HeartbeatSample> listen_heartbeats(const std::string& url, double seconds);

std::string own_host_name();

}  // namespace bricklayer::doctor
