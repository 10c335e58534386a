#include "rig.h"

#include <stdexcept>

namespace bricklayer::harness {

Rig::Rig(int64_t step_us, int64_t start_utime) : hub_(start_utime), step_us_(step_us), peer_(hub_.endpoint("test")) {
  if (step_us <= 0) throw std::invalid_argument("a rig step must be at least 1 us");
}

Recorder& Rig::record(const std::vector<std::string>& channels) {
  runtime::Bus& bus = hub_.endpoint("recorder");
  recorder_buses_.push_back(&bus);
  recorders_.push_back(std::make_unique<Recorder>(
      bus, channels, [this] { step(); }, [this] { return hub_.now_utime(); }));
  return *recorders_.back();
}

void Rig::publish_bytes(const std::string& channel, const std::vector<uint8_t>& bytes) {
  peer_.publish(channel, bytes.data(), bytes.size());
}

void Rig::handle_all() {
  for (auto& n : nodes_) n->step(0);
  for (runtime::Bus* b : recorder_buses_) b->handle(0);
  peer_.handle(0);
}

void Rig::settle() { hub_.settle([this] { handle_all(); }); }

void Rig::step() {
  settle();
  hub_.advance(step_us_);
  handle_all();
  settle();
}

void Rig::run_for(std::chrono::microseconds duration) {
  const int64_t until = hub_.now_utime() + duration.count();
  while (hub_.now_utime() < until) step();
}

bool Rig::run_until(const std::function<bool()>& pred, std::chrono::microseconds max) {
  const int64_t until = hub_.now_utime() + max.count();
  while (!pred()) {
    if (hub_.now_utime() >= until) return false;
    step();
  }
  return true;
}

}  // namespace bricklayer::harness
