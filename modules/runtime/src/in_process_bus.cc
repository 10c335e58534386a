#include "bricklayer/runtime/in_process_bus.h"

#include <stdexcept>
#include <string>

namespace bricklayer::runtime {

class InProcessBus::Endpoint final : public Bus {
 public:
  Endpoint(InProcessBus& hub, std::string name) : hub_(hub), name_(std::move(name)) {}

  bool publish(const std::string& channel, const uint8_t* data, size_t size) override {
    if (hub_.down_) return false;
    hub_.deliver(*this, channel, data, size);
    return true;
  }
  const SubscriptionStats& subscribe(const std::string& channel, QueuePolicy policy, Handler handler) override {
    return queues_.add(channel, policy, std::move(handler));
  }
  int handle(int) override { return queues_.dispatch(); }
  int64_t now_utime() const override { return hub_.now_; }
  std::string problem() const override { return hub_.down_ ? "in-process bus is down" : ""; }
  std::string describe() const override { return "in-process" + (name_.empty() ? "" : " (" + name_ + ")"); }

  const std::string& name() const { return name_; }
  SubscriptionQueues& queues() { return queues_; }
  const SubscriptionQueues& queues() const { return queues_; }

 private:
  InProcessBus& hub_;
  std::string name_;
  SubscriptionQueues queues_;
};

InProcessBus::InProcessBus(int64_t start_utime) : now_(start_utime) {}
InProcessBus::~InProcessBus() = default;

Bus& InProcessBus::endpoint(const std::string& name) {
  endpoints_.push_back(std::make_unique<Endpoint>(*this, name));
  return *endpoints_.back();
}

void InProcessBus::set_utime(int64_t utime) {
  if (utime < now_) throw std::invalid_argument("the in-process clock never runs backwards");
  now_ = utime;
}

void InProcessBus::advance(int64_t microseconds) {
  if (microseconds < 0) throw std::invalid_argument("the in-process clock never runs backwards");
  now_ += microseconds;
}

bool InProcessBus::pending() const {
  for (const auto& e : endpoints_)
    if (!e->queues().empty()) return true;
  return false;
}

int InProcessBus::settle(const std::function<void()>& handle_round, int max_rounds) {
  int rounds = 0;
  for (; pending(); ++rounds) {
    if (rounds >= max_rounds)
      throw std::runtime_error("the nodes keep answering each other (more than " + std::to_string(max_rounds) +
                               " rounds without the bus falling quiet)");
    handle_round();
  }
  return rounds;
}

void InProcessBus::deliver(const Endpoint& from, const std::string& channel, const uint8_t* data, size_t size) {
  if (tap_) tap_(from.name(), channel, data, size, now_);
  for (auto& e : endpoints_) e->queues().enqueue(channel, data, size, now_);
}

}  // namespace bricklayer::runtime
