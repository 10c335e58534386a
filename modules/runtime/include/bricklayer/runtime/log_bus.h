// A recorded log as a bus (Drake's DrakeLcmLog and LcmDrivenLoop in spirit): the log's events on the
// channels the node subscribes to are delivered in order, one per handle(), as fast as the node
// consumes them; the clock is each event's recorded utime, never the wall clock. A handle(timeout)
// whose timeout ends before the next event moves the clock to the end of the timeout and delivers
// nothing, so a node's timers (ticks, heartbeats, hold times) fire at the same recorded moments in
// every replay. What the node publishes goes to an output callback (a replay compares or records
// it), never back into the node: the log already holds what the live bus looped back.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/runtime/subscription_queues.h"

namespace bricklayer::runtime {

struct LogBusOptions {
  int64_t from_utime = 0;          // events before this are skipped (0: from the start)
  int64_t to_utime = INT64_MAX;    // the bus ends at the first event after this
  std::vector<std::string> exclude;  // channels never delivered (e.g. replaced by a replayed module's outputs)
};

class LogBus final : public Bus {
 public:
  using Output = std::function<void(const std::string& channel, const uint8_t* data, size_t size, int64_t utime)>;

  // Throws std::runtime_error when the log cannot be opened.
  explicit LogBus(const std::string& path, LogBusOptions options = {}, Output output = {});

  bool publish(const std::string& channel, const uint8_t* data, size_t size) override;
  const SubscriptionStats& subscribe(const std::string& channel, QueuePolicy policy, Handler handler) override;
  int handle(int timeout_ms) override;
  int64_t now_utime() const override { return now_; }
  std::string describe() const override { return "log " + reader_.path(); }

  // The log's damaged regions met so far (torn or truncated events): a replay must report them.
  const std::vector<LogDamage>& damage() const { return reader_.damage(); }
  const LogReader& reader() const { return reader_; }
  int64_t events_read() const { return events_read_; }
  int64_t events_delivered() const { return events_delivered_; }
  bool ended() const { return ended_; }

 private:
  bool peek();  // fills next_ with the next event worth delivering; false at the end

  LogReader reader_;
  LogBusOptions options_;
  Output output_;
  SubscriptionQueues queues_;
  std::optional<LogEvent> next_;
  int64_t now_ = 0;
  bool ended_ = false;
  int64_t events_read_ = 0;
  int64_t events_delivered_ = 0;
};

}  // namespace bricklayer::runtime
