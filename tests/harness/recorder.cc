#include "recorder.h"

#include "bricklayer/common/channels.h"

namespace bricklayer::harness {

Recorder::Recorder(runtime::Bus& bus, const std::vector<std::string>& channels, std::function<void()> pump,
                   std::function<int64_t()> clock_us)
    : pump_(std::move(pump)), clock_us_(std::move(clock_us)) {
  for (const std::string& c : channels) {
    bus.subscribe(c, runtime::QueuePolicy::keep(size_t{1} << 20), [this](const runtime::Received& r) {
      messages_.push_back(Message{r.channel, std::vector<uint8_t>(r.data, r.data + r.size), r.utime});
    });
  }
}

Recorder Recorder::live(runtime::Bus& bus, const std::vector<std::string>& channels) {
  return Recorder(
      bus, channels, [&bus] { bus.handle(5); },
      [] {
        return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
            .count();
      });
}

size_t Recorder::count(const std::string& channel) const {
  size_t n = 0;
  for (const Message& m : messages_) n += m.channel == channel;
  return n;
}

bool Recorder::wait_until(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const int64_t deadline = clock_us_() + timeout.count() * 1000;
  while (!pred()) {
    if (clock_us_() >= deadline) return false;
    pump_();
  }
  return true;
}

void Recorder::pump_for(std::chrono::milliseconds duration) {
  const int64_t until = clock_us_() + duration.count() * 1000;
  while (clock_us_() < until) pump_();
}

std::optional<heartbeat_t> Recorder::wait_for_heartbeat(const std::string& module,
                                                        const std::function<bool(const heartbeat_t&)>& pred,
                                                        std::chrono::milliseconds timeout) {
  return wait_for<heartbeat_t>(
      channel(kHeartbeatChannel), [&](const heartbeat_t& hb) { return hb.module == module && (!pred || pred(hb)); },
      timeout);
}

std::optional<heartbeat_t> Recorder::last_heartbeat(const std::string& module) const {
  std::optional<heartbeat_t> out;
  for (const heartbeat_t& hb : all<heartbeat_t>(channel(kHeartbeatChannel)))
    if (hb.module == module) out = hb;
  return out;
}

std::optional<double> heartbeat_value(const heartbeat_t& hb, const std::string& name) {
  for (size_t i = 0; i < hb.value_names.size() && i < hb.values.size(); ++i)
    if (hb.value_names[i] == name) return hb.values[i];
  return std::nullopt;
}

}  // namespace bricklayer::harness
