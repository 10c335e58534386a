#include "bricklayer/common/module.h"

#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"

namespace bricklayer {
namespace {
std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop = true; }
}  // namespace

int64_t wall_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Module::Module(std::string name, const std::string& url)
    : name_(std::move(name)), lcm_(std::make_unique<lcm::LCM>(url)), started_(std::chrono::steady_clock::now()) {
  log::set_module(name_);
  // good() stays true when multicast receive is broken; a valid file descriptor is the real check.
  if (!lcm_->good() || lcm_->getFileno() < 0) {
    throw std::runtime_error("cannot open the LCM bus at '" + url +
                             "' (is multicast routed? try: ip route add 224.0.0.0/4 dev lo)");
  }
  if (const char* r = std::getenv("BRICKLAYER_RESTARTS")) restarts_ = std::atoi(r);
}

Module::~Module() = default;

void Module::trampoline(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Subscription* sub) {
  Module& self = *sub->module;
  try {
    if (rbuf->data_size > sub->max_bytes) {
      ++self.counters_.errors;
      log::warn("rejected ", rbuf->data_size, "-byte message on ", channel, " (limit ", sub->max_bytes, ")");
      return;
    }
    if (!sub->handler(rbuf->data, rbuf->data_size)) {
      ++self.counters_.errors;
      log::warn("could not decode a ", rbuf->data_size, "-byte message on ", channel,
                " (malformed or another message type)");
      return;
    }
    ++self.counters_.received;
  } catch (const std::exception& e) {
    ++self.counters_.errors;
    log::error("handler for ", channel, " failed: ", e.what());
  } catch (...) {
    ++self.counters_.errors;
    log::error("handler for ", channel, " failed with an unknown exception");
  }
}

void Module::subscribe_raw(const std::string& channel, RawHandler handler, size_t max_bytes, int queue_capacity) {
  subscriptions_.push_back(Subscription{this, channel, max_bytes, std::move(handler)});
  lcm::Subscription* s = lcm_->subscribeFunction(channel, &Module::trampoline, &subscriptions_.back());
  if (s) s->setQueueCapacity(queue_capacity);
}

void Module::publish_heartbeat() {
  heartbeat_t hb{};
  hb.utime = wall_utime();
  hb.module = name_;
  char host[256] = {0};
  gethostname(host, sizeof(host) - 1);
  hb.pid = static_cast<int32_t>(getpid());
  hb.instance = std::string(host) + ":" + std::to_string(hb.pid);
  hb.uptime_us =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - started_).count();
  hb.received = counters_.received;
  hb.published = counters_.published;
  hb.dropped = counters_.dropped;
  hb.errors = counters_.errors;
  hb.restarts = restarts_;
  hb.status = status_;
  for (const auto& [key, value] : values_) {
    hb.value_names.push_back(key);
    hb.values.push_back(value);
  }
  hb.num_values = static_cast<int32_t>(hb.values.size());
  // Not counted as "published": counters describe the module's data flow.
  lcm_->publish(channel(kHeartbeatChannel), &hb);
}

int Module::run(const std::function<void()>& tick, int tick_ms, int heartbeat_ms) {
  install_signal_handlers();
  auto next_heartbeat = std::chrono::steady_clock::now();
  while (!g_stop) {
    auto now = std::chrono::steady_clock::now();
    if (now >= next_heartbeat) {
      publish_heartbeat();
      next_heartbeat = now + std::chrono::milliseconds(heartbeat_ms);
    }
    int rc = lcm_->handleTimeout(tick_ms);
    if (rc < 0) {
      if (g_stop) break;
      ++counters_.errors;
      log::error("LCM receive failed; retrying");
      continue;
    }
    // Drain whatever else is already queued so tick() sees only the newest input.
    while (rc > 0 && !g_stop) rc = lcm_->handleTimeout(0);
    try {
      if (tick) tick();
    } catch (const std::exception& e) {
      ++counters_.errors;
      log::error("processing failed: ", e.what());
    }
  }
  log::info("stopping: received ", counters_.received.load(), ", published ", counters_.published.load(),
            ", dropped ", counters_.dropped.load(), ", errors ", counters_.errors.load());
  publish_heartbeat();
  return 0;
}

void Module::install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: let poll() return so the loop notices at once
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
}

bool Module::stop_requested() { return g_stop; }
void Module::request_stop() { g_stop = true; }

}  // namespace bricklayer
