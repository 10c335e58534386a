#include "bricklayer/runtime/log_bus.h"

#include <algorithm>

namespace bricklayer::runtime {

LogBus::LogBus(const std::string& path, LogBusOptions options, Output output)
    : reader_(path), options_(std::move(options)), output_(std::move(output)) {
  // The clock starts at the first event of the range, before any node reads it (a node's start time,
  // its first heartbeat and its timers count from there).
  LogEvent e;
  while (reader_.next(e)) {
    if (e.utime >= options_.from_utime) {
      now_ = e.utime;
      reader_.seek(e.offset);
      return;
    }
  }
  reader_.seek(0);
}

bool LogBus::publish(const std::string& channel, const uint8_t* data, size_t size) {
  if (output_) output_(channel, data, size, now_);
  return true;
}

const SubscriptionStats& LogBus::subscribe(const std::string& channel, QueuePolicy policy, Handler handler) {
  return queues_.add(channel, policy, std::move(handler));
}

bool LogBus::peek() {
  while (!next_ && !ended_) {
    LogEvent e;
    if (!reader_.next(e)) {
      ended_ = true;
      break;
    }
    ++events_read_;
    if (e.utime < options_.from_utime) continue;
    if (e.utime > options_.to_utime) {
      ended_ = true;
      break;
    }
    if (!queues_.wanted(e.channel)) continue;
    if (std::find(options_.exclude.begin(), options_.exclude.end(), e.channel) != options_.exclude.end()) continue;
    next_ = std::move(e);
  }
  return next_.has_value();
}

int LogBus::handle(int timeout_ms) {
  if (!queues_.empty()) return queues_.dispatch();
  if (!peek()) return kEnded;
  const int64_t deadline = now_ + int64_t{std::max(0, timeout_ms)} * 1000;
  if (next_->utime > deadline) {
    now_ = deadline;
    return 0;
  }
  // Recorders stamp on receipt, and several publishers can interleave: keep the clock monotone.
  now_ = std::max(now_, next_->utime);
  queues_.enqueue(next_->channel, next_->data.data(), next_->data.size(), now_);
  next_.reset();
  ++events_delivered_;
  return queues_.dispatch();
}

}  // namespace bricklayer::runtime
