// The live bus of a process test: LCM udpm on loopback inside the test's own network namespace (NETNS
// tests run under tests/netns/run-in-netns, so nothing leaves the machine and parallel cases cannot
// hear each other), and a typed publish for the test playing a peer on it.
//
//   runtime::LcmBus bus(harness::kLiveUrl);
//   auto rec = harness::Recorder::live(bus, {channel(kPredictionChannel)});
//   REQUIRE(harness::publish(bus, channel(kStackChannel), stack));
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::harness {

inline constexpr const char* kLiveUrl = "udpm://239.255.76.67:7667?ttl=0";

// Encodes msg and publishes it; false when the bus refused it.
template <typename T>
bool publish(runtime::Bus& bus, const std::string& channel, const T& msg) {
  const std::vector<uint8_t> bytes = runtime::encode(msg);
  return bus.publish(channel, bytes.data(), bytes.size());
}

// Publishes raw bytes (garbage, truncated or oversized messages for the bad-input tests).
inline bool publish_bytes(runtime::Bus& bus, const std::string& channel, const std::vector<uint8_t>& bytes) {
  return bus.publish(channel, bytes.data(), bytes.size());
}

}  // namespace bricklayer::harness
