// Nodes on an in-process bus, driven by the test: one thread, a deterministic order, and a clock that
// moves only when the rig steps it, so a minute of a module's life runs in milliseconds and every run
// is the same. A step lets every node handle what is queued (until nothing is), then advances the
// clock by step_us and lets every node tick.
//
//   harness::Rig rig;
//   auto& prediction = rig.add<prediction::PredictionNode>(config);
//   auto& rec = rig.record({channel(kPredictionChannel)});
//   rig.publish(channel(kStackChannel), stack);
//   auto p = rec.wait_for<prediction_t>(channel(kPredictionChannel));
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/in_process_bus.h"
#include "bricklayer/runtime/node.h"
#include "recorder.h"

namespace bricklayer::harness {

class Rig {
 public:
  explicit Rig(int64_t step_us = 1000, int64_t start_utime = runtime::InProcessBus::kDefaultStartUtime);

  runtime::InProcessBus& hub() { return hub_; }
  int64_t now() const { return hub_.now_utime(); }

  // Builds a node on a new endpoint: NodeType(args..., bus). The rig owns it.
  template <typename NodeType, typename... Args>
  NodeType& add(Args&&... args) {
    auto node = std::make_unique<NodeType>(std::forward<Args>(args)..., hub_.endpoint("node " + std::to_string(nodes_.size())));
    NodeType& ref = *node;
    nodes_.push_back(std::move(node));
    return ref;
  }

  // A recorder of these channels; waits are measured in the rig's clock and step the rig.
  Recorder& record(const std::vector<std::string>& channels);

  // Publishes as a test-side peer would (through an endpoint of its own).
  template <typename T>
  void publish(const std::string& channel, const T& msg) {
    const std::vector<uint8_t> bytes = runtime::encode(msg);
    publish_bytes(channel, bytes);
  }
  void publish_bytes(const std::string& channel, const std::vector<uint8_t>& bytes);

  // Every node handles what is queued, repeatedly, until nothing is (bounded: a node that keeps
  // answering itself is a failure, thrown as std::runtime_error).
  void settle();
  // settle(), advance the clock by step_us, let every node tick, settle().
  void step();
  void run_for(std::chrono::microseconds duration);
  // Steps until pred() holds (checked after every step) or max passes; returns pred().
  bool run_until(const std::function<bool()>& pred, std::chrono::microseconds max);

 private:
  void handle_all();

  runtime::InProcessBus hub_;
  int64_t step_us_;
  std::vector<std::unique_ptr<runtime::Node>> nodes_;
  runtime::Bus& peer_;
  std::vector<runtime::Bus*> recorder_buses_;
  std::vector<std::unique_ptr<Recorder>> recorders_;
};

}  // namespace bricklayer::harness
