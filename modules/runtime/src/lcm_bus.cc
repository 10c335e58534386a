#include "bricklayer/runtime/lcm_bus.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <thread>

#include "bricklayer/common/log.h"

namespace bricklayer::runtime {
namespace {
// At most this many messages are taken from LCM per handle(), so a flood cannot starve the node.
constexpr int kMaxDrainPerHandle = 10000;

// LCM prints ten lines to stderr each time it cannot open the bus. Once the first attempt has said so
// (and our own warning names the problem), retries once a second would fill a journal in a day: they
// run with stderr pointed at /dev/null for the moment the constructor takes.
class QuietStderr {
 public:
  explicit QuietStderr(bool quiet) {
    if (!quiet) return;
    std::fflush(stderr);
    saved_ = ::dup(2);
    const int null = ::open("/dev/null", O_WRONLY);
    if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    if (saved_ < 0) return;
    std::fflush(stderr);
    ::dup2(saved_, 2);
    ::close(saved_);
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_ = -1;
};

int64_t wall_now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}
}  // namespace

LcmBus::LcmBus(std::string url, LcmBusOptions options)
    : url_(std::move(url)), options_(std::move(options)), steady_start_(Steady::now()), wall_start_utime_(wall_now_utime()) {
  try_open();
}

LcmBus::~LcmBus() = default;

int64_t LcmBus::now_utime() const {
  // Wall time at start plus steady time since: monotone, and still readable as a date.
  return wall_start_utime_ + std::chrono::duration_cast<std::chrono::microseconds>(Steady::now() - steady_start_).count();
}

void LcmBus::try_open() {
  next_open_attempt_ = Steady::now() + std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(options_.reopen_every_s));
  std::unique_ptr<lcm::LCM> lcm;
  {
    QuietStderr quiet(!problem_.empty());
    lcm = std::make_unique<lcm::LCM>(url_);
  }
  // good() stays true when multicast receive is broken; a valid file descriptor is the real check.
  if (!lcm->good() || lcm->getFileno() < 0) {
    const std::string why = "cannot open the LCM bus at '" + url_ +
                            "' (no multicast route? launch/bricklayer and bricklayer-doctor say how to add it); retrying";
    if (problem_ != why) log::warn(why);
    problem_ = why;
    return;
  }
  lcm_ = std::move(lcm);
  for (ChannelContext& c : contexts_) subscribe_on_lcm(c);
  // The loopback check needs this process's own messages back, whether or not a node subscribes to
  // that channel (a camera subscribes to nothing): LCM delivers only what is subscribed.
  if (!options_.loopback_channel.empty())
    lcm_->subscribeFunction(options_.loopback_channel, &LcmBus::on_own_message, this);
  if (ever_open_) {
    ++reopens_;
    log::info("LCM bus at ", url_, " open again");
  }
  ever_open_ = true;
  problem_.clear();
  last_heard_ = Steady::now();
  unheard_publish_ = false;
}

void LcmBus::close(const std::string& why) {
  if (problem_ != why) log::warn(why);
  problem_ = why;
  lcm_.reset();
  next_open_attempt_ = Steady::now() + std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(options_.reopen_every_s));
}

void LcmBus::subscribe_on_lcm(ChannelContext& context) {
  lcm::Subscription* s = lcm_->subscribeFunction(context.channel, &LcmBus::on_message, &context);
  // Generous: SubscriptionQueues applies the real policy at every handle(); LCM would otherwise
  // discard silently beyond its default of 30.
  if (s) s->setQueueCapacity(options_.lcm_queue_capacity);
}

void LcmBus::on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, ChannelContext* context) {
  LcmBus& self = *context->bus;
  self.last_heard_ = Steady::now();
  self.unheard_publish_ = false;
  // Nothing may throw across LCM's C callback: enqueue only copies bytes (bad_alloc aside).
  try {
    self.queues_.enqueue_for(context->channel, channel, static_cast<const uint8_t*>(rbuf->data), rbuf->data_size,
                             self.now_utime());
  } catch (...) {
  }
}

void LcmBus::on_own_message(const lcm::ReceiveBuffer*, const std::string&, LcmBus* self) {
  self->last_heard_ = Steady::now();
  self->unheard_publish_ = false;
}

bool LcmBus::publish(const std::string& channel, const uint8_t* data, size_t size) {
  if (!lcm_) return false;
  if (lcm_->publish(channel, data, static_cast<unsigned int>(size)) != 0) {
    // A send fails while the multicast route is gone; the socket itself may still be fine.
    problem_ = "cannot send on the LCM bus at '" + url_ + "' (no multicast route?)";
    return false;
  }
  if (channel == options_.loopback_channel && !unheard_publish_) {
    unheard_publish_ = true;
    first_unheard_publish_ = Steady::now();
  }
  if (problem_.rfind("cannot send", 0) == 0) problem_.clear();
  return true;
}

const SubscriptionStats& LcmBus::subscribe(const std::string& channel, QueuePolicy policy, Handler handler) {
  const auto& patterns = queues_.patterns();
  const bool known = std::find(patterns.begin(), patterns.end(), channel) != patterns.end();
  const SubscriptionStats& stats = queues_.add(channel, policy, std::move(handler));
  if (!known) {
    contexts_.push_back(ChannelContext{this, channel});
    if (lcm_) subscribe_on_lcm(contexts_.back());
  }
  return stats;
}

void LcmBus::check_loopback() {
  if (options_.loopback_channel.empty() || !unheard_publish_) return;
  const auto now = Steady::now();
  const auto silence = std::chrono::duration<double>(options_.silence_s);
  if (now - first_unheard_publish_ > silence && now - last_heard_ > silence) {
    close("heard nothing on the LCM bus at '" + url_ + "' for " + std::to_string(static_cast<int>(options_.silence_s)) +
          " s, not even this process's own messages (interface down?); reopening");
  }
}

int LcmBus::handle(int timeout_ms) {
  timeout_ms = std::max(0, timeout_ms);
  if (!lcm_) {
    if (Steady::now() >= next_open_attempt_) try_open();
    if (!lcm_) {
      const auto wait = std::min<Steady::duration>(std::chrono::milliseconds(timeout_ms), next_open_attempt_ - Steady::now());
      if (wait > Steady::duration::zero()) std::this_thread::sleep_for(wait);
      return queues_.dispatch();
    }
  }
  // Leftovers from an earlier drain are delivered without waiting.
  const int wait_ms = queues_.empty() ? timeout_ms : 0;
  pollfd fd{lcm_->getFileno(), POLLIN, 0};
  const int ready = ::poll(&fd, 1, wait_ms);
  if (ready < 0 && errno != EINTR) {
    close("waiting on the LCM bus at '" + url_ + "' failed; reopening");
  } else if (ready > 0) {
    for (int k = 0; k < kMaxDrainPerHandle; ++k) {
      const int rc = lcm_->handleTimeout(0);
      if (rc == 0) break;
      if (rc < 0) {
        close("receiving on the LCM bus at '" + url_ + "' failed; reopening");
        break;
      }
    }
  }
  if (lcm_) check_loopback();
  return queues_.dispatch();
}

}  // namespace bricklayer::runtime
