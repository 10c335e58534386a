#include "bricklayer/doctor/clock_check.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/doctor/quiet_stderr.h"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/heartbeat_t.hpp"

namespace bricklayer::doctor {

std::string own_host_name() {
  char host[256] = {};
  gethostname(host, sizeof(host) - 1);
  return host;
}

std::vector<PeerOffset> estimate_offsets(const std::vector<HeartbeatSample>& samples, const std::string& own_host) {
  std::map<std::string, std::pair<int64_t, int64_t>> range;  // host -> (min, max) difference
  std::map<std::string, int> counts;
  for (const auto& s : samples) {
    const std::string host = s.instance.substr(0, s.instance.rfind(':'));
    if (host.empty() || host == own_host) continue;
    const int64_t d = s.received_utime - s.sent_utime;
    auto [it, fresh] = range.try_emplace(host, d, d);
    if (!fresh) {
      it->second.first = std::min(it->second.first, d);
      it->second.second = std::max(it->second.second, d);
    }
    ++counts[host];
  }
  std::vector<PeerOffset> out;
  for (const auto& [host, r] : range)
    out.push_back({host, r.first / 1000.0, (r.second - r.first) / 1000.0, counts[host]});
  return out;
}

CheckResult judge_clock(const HostPlan& plan, const std::vector<PeerOffset>& peers, double listened_s) {
  const std::string name = "clock";
  if (!plan.two_hosts && peers.empty()) return CheckResult::ok(name, "one host: no other clock to agree with");
  char seconds[32];
  std::snprintf(seconds, sizeof(seconds), "%.0f s", listened_s);
  if (peers.empty())
    return CheckResult::warning(name, std::string("no heartbeat from another host in ") + seconds + ": the offset is not known",
                                "start the other host's profile (or bricklayer-doctor there at the same time) and run this again");
  const std::string sync = "run NTP on both hosts against the same server (timedatectl set-ntp true, or chrony)";
  std::string detail;
  double worst = 0;
  for (const auto& p : peers) {
    char text[160];
    std::snprintf(text, sizeof(text), "%s%s is %.1f ms %s (%d heartbeats, delay spread %.1f ms)", detail.empty() ? "" : "; ",
                  p.host.c_str(), std::abs(p.offset_ms), p.offset_ms >= 0 ? "behind" : "ahead", p.samples, p.spread_ms);
    detail += text;
    worst = std::max(worst, std::abs(p.offset_ms));
  }
  if (worst > kClockWarningMs)
    return CheckResult::warning(name, detail + ": latencies measured across the hosts and the log's order are off", sync);
  return CheckResult::ok(name, detail);
}

std::vector<HeartbeatSample> listen_heartbeats(const std::string& url, double seconds) {
  QuietStderr quiet;
  runtime::LcmBus bus(url);
  if (!bus.open()) throw std::runtime_error("cannot open " + url + ": " + bus.problem());
  std::vector<HeartbeatSample> samples;
  const std::string heartbeats = channel(kHeartbeatChannel);
  // Every heartbeat counts (several per second from each of the other host's modules).
  bus.subscribe(heartbeats, runtime::QueuePolicy::keep(1000), [&](const runtime::Received& m) {
    if (auto hb = runtime::decode<heartbeat_t>(m.data, m.size)) samples.push_back({hb->module, hb->instance, hb->utime, m.utime});
  });
  heartbeat_t own{};
  own.module = "doctor";
  own.pid = static_cast<int32_t>(getpid());
  own.instance = own_host_name() + ":" + std::to_string(own.pid);
  own.status = "checking the clock";
  const auto start = std::chrono::steady_clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  auto next_heartbeat = start;
  while (std::chrono::steady_clock::now() < end) {
    if (std::chrono::steady_clock::now() >= next_heartbeat) {
      own.utime = bus.now_utime();
      own.uptime_us = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();
      const std::vector<uint8_t> bytes = runtime::encode(own);
      bus.publish(heartbeats, bytes.data(), bytes.size());
      next_heartbeat += std::chrono::seconds(1);
    }
    bus.handle(20);
  }
  return samples;
}

}  // namespace bricklayer::doctor
