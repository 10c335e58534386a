#include "bricklayer/runtime/node.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/log.h"
#include "bricklayer/node_config_t.hpp"

namespace bricklayer::runtime {
namespace {
constexpr int64_t kHeartbeatPeriodUs = 1'000'000;
constexpr int64_t kConfigEveryHeartbeats = 10;

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop = true; }

std::string host_name() {
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  return host;
}

std::string seconds_text(int64_t us) { return std::to_string((us + 500'000) / 1'000'000) + " s"; }
}  // namespace

Node::Node(std::string name, Bus& bus)
    : name_(std::move(name)),
      bus_(bus),
      heartbeat_channel_(channel(kHeartbeatChannel)),
      config_channel_(channel(kConfigChannel)),
      pid_(static_cast<int32_t>(getpid())),
      start_utime_(bus.now_utime()),
      next_heartbeat_utime_(bus.now_utime()) {
  log::set_module(name_);
  instance_ = host_name() + ":" + std::to_string(pid_);
  if (const char* r = std::getenv("BRICKLAYER_RESTARTS")) restarts_ = std::atoi(r);
}

Node::~Node() = default;

void Node::set_config(std::string program, std::string config_json) {
  program_ = std::move(program);
  config_json_ = std::move(config_json);
}

namespace {
// The transport's queue for one subscription: inputs are decoded (and bad ones counted) as soon as the
// step's wait ends, so this only has to hold one burst; a flood beyond it is counted as dropped.
constexpr size_t kTransportQueue = 4096;
}  // namespace

void Node::subscribe_raw(const std::string& channel, QueuePolicy policy, size_t max_bytes, Decoder decoder) {
  if (policy.capacity == 0) throw std::invalid_argument("a subscription queue needs a capacity of at least 1");
  inboxes_.push_back(Inbox{channel, policy, {}, 0});
  Inbox& inbox = inboxes_.back();
  const SubscriptionStats& stats = bus_.subscribe(
      channel, QueuePolicy::keep(kTransportQueue), [this, &inbox, max_bytes, decoder = std::move(decoder)](const Received& r) {
        last_message_utime_[r.channel] = r.utime;
        if (r.size > max_bytes) {
          error("oversized messages on " + r.channel, "rejected a " + std::to_string(r.size) + "-byte message on " +
                                                          r.channel + " (limit " + std::to_string(max_bytes) + ")");
          return;
        }
        std::function<void()> call;
        try {
          call = decoder(r);
        } catch (const std::exception& e) {
          error("malformed messages on " + r.channel, "decoding a message on " + r.channel + " failed: " + e.what());
          return;
        }
        if (!call) {
          error("malformed messages on " + r.channel, "could not decode a " + std::to_string(r.size) + "-byte message on " +
                                                          r.channel + " (malformed or another message type)");
          return;
        }
        ++counters_.received;
        if (inbox.queue.size() >= inbox.policy.capacity) {
          inbox.queue.pop_front();
          ++inbox.dropped;
        }
        inbox.queue.push_back(Pending{next_sequence_++, std::move(call)});
      });
  subscription_stats_.push_back(&stats);
}

void Node::subscribe_bytes(const std::string& pattern, QueuePolicy policy, std::function<void(const Received&)> handler,
                           size_t max_bytes) {
  subscribe_raw(pattern, policy, max_bytes, [handler = std::move(handler)](const Received& r) -> std::function<void()> {
    return [handler, channel = r.channel, bytes = std::vector<uint8_t>(r.data, r.data + r.size), utime = r.utime] {
      handler(Received{channel, bytes.data(), bytes.size(), utime});
    };
  });
}

void Node::deliver_pending() {
  for (;;) {
    Inbox* next = nullptr;
    for (Inbox& in : inboxes_)
      if (!in.queue.empty() && (!next || in.queue.front().sequence < next->queue.front().sequence)) next = &in;
    if (!next) return;
    const std::function<void()> call = std::move(next->queue.front().call);
    const std::string& channel = next->channel;
    next->queue.pop_front();
    // Nothing a handler does may escape into the bus (LCM's C callback, a test's loop).
    try {
      call();
    } catch (const std::exception& e) {
      error("failed handlers on " + channel, "handling a message on " + channel + " failed: " + e.what());
    } catch (...) {
      error("failed handlers on " + channel, "handling a message on " + channel + " failed");
    }
  }
}

bool Node::publish_bytes(const std::string& channel, const std::vector<uint8_t>& bytes, bool output) {
  if (!bus_.publish(channel, bytes.data(), bytes.size())) {
    error("refused publications on " + channel, "publishing on " + channel + " failed" +
                                                     (bus_.problem().empty() ? "" : ": " + bus_.problem()));
    return false;
  }
  if (output) ++counters_.published;
  return true;
}

void Node::error(const std::string& kind, const std::string& message) {
  ++counters_.errors;
  warnings_.warn(kind, message, now());
}

void Node::warn(const std::string& kind, const std::string& message) { warnings_.warn(kind, message, now()); }

void Node::wake_at(int64_t utime) { wake_utime_ = std::min(wake_utime_, utime); }

void Node::watch_input(const std::string& channel, double after_s, std::string what) {
  watches_.push_back(Watch{channel, static_cast<int64_t>(after_s * 1e6), std::move(what)});
}

int64_t Node::silent_for_us(const std::string& channel) const {
  auto it = last_message_utime_.find(channel);
  return now() - (it == last_message_utime_.end() ? start_utime_ : it->second);
}

std::string Node::stale_inputs() const {
  for (const Watch& w : watches_) {
    const int64_t silent = silent_for_us(w.channel);
    if (silent > w.after_us) return w.what + " for " + seconds_text(silent);
  }
  return "";
}

std::string Node::status() const {
  std::vector<std::string> parts;
  if (const std::string p = bus_.problem(); !p.empty()) parts.push_back(p);
  if (const std::string s = stale_inputs(); !s.empty()) parts.push_back(s);
  if (status_ != "ok" && !status_.empty()) parts.push_back(status_);
  if (parts.empty()) return "ok";
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : "; ") + p;
  return out;
}

int64_t Node::queue_drops() const {
  int64_t n = 0;
  for (const SubscriptionStats* s : subscription_stats_) n += s->dropped;
  for (const Inbox& in : inboxes_) n += in.dropped;
  return n;
}

heartbeat_t Node::heartbeat() const {
  heartbeat_t hb{};
  hb.utime = now();
  hb.module = name_;
  hb.instance = instance_;
  hb.pid = pid_;
  hb.uptime_us = now() - start_utime_;
  hb.received = counters_.received;
  hb.published = counters_.published;
  hb.dropped = counters_.dropped + queue_drops();
  hb.errors = counters_.errors;
  hb.restarts = restarts_;
  hb.status = status();
  for (const auto& [key, value] : values_) {
    hb.value_names.push_back(key);
    hb.values.push_back(value);
  }
  hb.num_values = static_cast<int32_t>(hb.values.size());
  return hb;
}

void Node::publish_heartbeat() {
  try {
    before_heartbeat();
  } catch (const std::exception& e) {
    error("failed heartbeat updates", std::string("updating the heartbeat failed: ") + e.what());
  }
  // A heartbeat is a report, not an output; a refused one is not an error of the node's (the bus's
  // problem is in the next heartbeat that gets through).
  const std::vector<uint8_t> bytes = encode(heartbeat());
  bus_.publish(heartbeat_channel_, bytes.data(), bytes.size());
  if (!config_json_.empty() && heartbeats_ % kConfigEveryHeartbeats == 0) publish_config();
  ++heartbeats_;
  last_heartbeat_utime_ = now();
}

void Node::publish_config() {
  node_config_t c{};
  c.utime = now();
  c.module = name_;
  c.instance = instance_;
  c.program = program_;
  c.config_json = config_json_;
  const std::vector<uint8_t> bytes = encode(c);
  bus_.publish(config_channel_, bytes.data(), bytes.size());
}

bool Node::step(int timeout_ms) {
  const int64_t start = now();
  int64_t due = std::min(next_heartbeat_utime_, wake_utime_);
  const int64_t wait_us = std::clamp<int64_t>(due - start, 0, int64_t{std::max(0, timeout_ms)} * 1000);
  // Round up, so that a timer due in 0.3 ms is not polled for in a busy loop of zero waits.
  const int rc = bus_.handle(static_cast<int>((wait_us + 999) / 1000));
  if (rc == Bus::kEnded) return false;
  deliver_pending();
  if (now() >= wake_utime_) wake_utime_ = INT64_MAX;
  try {
    tick();
  } catch (const std::exception& e) {
    error("failed processing", std::string("processing failed: ") + e.what());
  } catch (...) {
    error("failed processing", "processing failed");
  }
  if (now() >= next_heartbeat_utime_) {
    publish_heartbeat();
    // Keep the 1 s rhythm on the clock's grid; after a long stall, start again from now.
    next_heartbeat_utime_ += kHeartbeatPeriodUs;
    if (next_heartbeat_utime_ <= now()) next_heartbeat_utime_ = now() + kHeartbeatPeriodUs;
  }
  warnings_.flush(now());
  return true;
}

int Node::run() {
  install_signal_handlers();
  while (!g_stop && !stopping_) {
    if (!step(tick_ms_)) break;
  }
  try {
    before_stop();
  } catch (const std::exception& e) {
    error("failed stops", std::string("finishing failed: ") + e.what());
  }
  log::info("stopping: received ", counters_.received, ", published ", counters_.published, ", dropped ",
            counters_.dropped + queue_drops(), ", errors ", counters_.errors);
  warnings_.flush(INT64_MAX);
  publish_heartbeat();
  return 0;
}

void Node::install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: poll() returns at once so the loop notices
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

bool Node::stop_requested() { return g_stop; }
void Node::request_stop() { g_stop = true; }

}  // namespace bricklayer::runtime
