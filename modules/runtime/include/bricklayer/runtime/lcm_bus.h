// The live exhibit's bus: LCM udpm. It never gives up: when the bus cannot be opened (no multicast
// route yet, the interface down) or stops working, publish() fails and handle() waits, while the bus
// reopens its socket once a second and subscribes again; problem() says what is wrong meanwhile, so
// the node reports it in its heartbeat instead of crash-looping.
//
// LCM 1.3.1's own per-subscription queue discards new messages silently when full (shared NOTES), so
// LCM's queues are kept large and drained at every handle() into SubscriptionQueues, where the
// node's QueuePolicy decides what is dropped, and counts it.
#pragma once

#include <chrono>
#include <list>
#include <memory>
#include <string>

#include "bricklayer/runtime/bus.h"
#include "bricklayer/runtime/subscription_queues.h"

namespace lcm {
class LCM;
class ReceiveBuffer;
}  // namespace lcm

namespace bricklayer::runtime {

struct LcmBusOptions {
  // A channel this process publishes regularly (its heartbeat). LCM udpm hears its own messages, so
  // when this process has been publishing but has heard nothing at all, not even itself, for
  // silence_s, receiving is broken (the interface went down and up) and the socket is reopened.
  // "" turns the check off.
  std::string loopback_channel;
  double silence_s = 3.0;
  double reopen_every_s = 1.0;
  // Messages LCM itself may hold per subscription between two handle() calls before it discards new
  // ones (LCM's default is 30); the node's own QueuePolicy applies after.
  int lcm_queue_capacity = 10000;
};

class LcmBus final : public Bus {
 public:
  // Never throws for an unreachable bus (see problem()); the URL should be checked beforehand
  // (check_lcm_url).
  explicit LcmBus(std::string url, LcmBusOptions options = {});
  ~LcmBus() override;
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  bool publish(const std::string& channel, const uint8_t* data, size_t size) override;
  const SubscriptionStats& subscribe(const std::string& channel, QueuePolicy policy, Handler handler) override;
  int handle(int timeout_ms) override;
  int64_t now_utime() const override;
  std::string problem() const override { return problem_; }
  std::string describe() const override { return url_; }

  bool open() const { return lcm_ != nullptr; }
  int reopens() const { return reopens_; }  // times the socket was opened again after a failure

 private:
  struct ChannelContext {
    LcmBus* bus;
    std::string channel;  // the pattern LCM matched
  };
  static void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, ChannelContext* context);
  static void on_own_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, LcmBus* self);
  void try_open();
  void close(const std::string& why);
  void subscribe_on_lcm(ChannelContext& context);
  void check_loopback();

  using Steady = std::chrono::steady_clock;
  std::string url_;
  LcmBusOptions options_;
  std::unique_ptr<lcm::LCM> lcm_;
  SubscriptionQueues queues_;
  std::list<ChannelContext> contexts_;  // one per distinct pattern; stable addresses for LCM's callbacks
  std::string problem_;
  int reopens_ = 0;
  bool ever_open_ = false;
  Steady::time_point next_open_attempt_{};
  Steady::time_point last_heard_{};
  Steady::time_point first_unheard_publish_{};
  bool unheard_publish_ = false;
  Steady::time_point steady_start_;
  int64_t wall_start_utime_;
};

}  // namespace bricklayer::runtime
