// bricklayer-bench-roundtrip: stack -> prediction round-trip latency across processes on the real LCM
// bus. Publishes a stack_t on BL_STACK, waits for the prediction_t with its frame_number on
// BL_PREDICTION, one at a time, and prints median and p99 per pile size. By default it starts its own
// bricklayer-prediction (from the directory of this binary) and stops it at the end.
//
// Subscribes: BL_PREDICTION (prediction_t), BL_TIMING (timing_t), BL_HEARTBEAT (heartbeat_t).
// Publishes:  BL_STACK (stack_t).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/launcher/process.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/prediction/verdict_hysteresis.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/timing_t.hpp"

namespace {

using namespace bricklayer;
using Clock = std::chrono::steady_clock;

class RoundTrip {
 public:
  explicit RoundTrip(const std::string& url) : bus_(url) {
    if (!bus_.open())
      throw std::runtime_error("cannot open the LCM bus at '" + url +
                               "'; multicast may not be routed here: run inside tests/netns/run-in-netns");
    // Queues deep enough that nothing is dropped between two handle() calls: a lost answer would be
    // counted as a lost round trip.
    bus_.subscribe(channel(kPredictionChannel), runtime::QueuePolicy::keep(1000), [this](const runtime::Received& r) {
      const auto p = runtime::decode<prediction_t>(r.data, r.size);
      if (p && p->frame_number == wanted_) got_.assign(r.data, r.data + r.size);
    });
    bus_.subscribe(channel(kTimingChannel), runtime::QueuePolicy::keep(1000), [this](const runtime::Received& r) {
      const auto t = runtime::decode<timing_t>(r.data, r.size);
      if (t && t->module == "prediction" && t->frame_number == wanted_) predict_us_ = static_cast<double>(t->elapsed_us);
    });
    bus_.subscribe(channel(kHeartbeatChannel), runtime::QueuePolicy::keep(100), [this](const runtime::Received& r) {
      const auto hb = runtime::decode<heartbeat_t>(r.data, r.size);
      if (hb && hb->module == "prediction") heartbeat_pid_ = hb->pid;
    });
  }

  // Waits until a prediction heartbeat (from pid, or any when pid <= 0) arrives.
  bool wait_for_prediction(pid_t pid, std::chrono::milliseconds timeout) {
    auto until = Clock::now() + timeout;
    while (Clock::now() < until) {
      bus_.handle(50);
      if (heartbeat_pid_ > 0 && (pid <= 0 || heartbeat_pid_ == pid)) return true;
    }
    return false;
  }

  // One round trip; the received bytes, or empty on timeout. latency_us and predict_us are filled.
  std::vector<uint8_t> ask(const stack_t& stack, std::chrono::milliseconds timeout, double& latency_us,
                           double& predict_us) {
    wanted_ = stack.frame_number;
    got_.clear();
    predict_us_ = -1;
    const std::vector<uint8_t> bytes = runtime::encode(stack);
    auto t0 = Clock::now();
    bus_.publish(channel(kStackChannel), bytes.data(), bytes.size());
    auto until = t0 + timeout;
    while (got_.empty() && Clock::now() < until) bus_.handle(5);
    latency_us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
    // The timing message follows the prediction; wait for it a little (a benchmark figure, not a check).
    auto timing_until = Clock::now() + std::chrono::milliseconds(20);
    while (!got_.empty() && predict_us_ < 0 && Clock::now() < timing_until) bus_.handle(2);
    predict_us = predict_us_;
    return got_;
  }

 private:
  runtime::LcmBus bus_;
  int64_t wanted_ = -1;
  std::vector<uint8_t> got_;
  double predict_us_ = -1;
  pid_t heartbeat_pid_ = 0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  size_t i = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size()))) ;
  return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
}

std::vector<int> parse_sizes(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      int n = std::stoi(item);
      if (n < 1 || n > 5000) throw std::out_of_range(item);
      out.push_back(n);
    } catch (const std::exception&) {
      throw FlagError("--blocks expects a comma-separated list of sizes between 1 and 5000, got '" + text + "'");
    }
  }
  if (out.empty()) throw FlagError("--blocks is empty");
  return out;
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-bench-roundtrip",
              "Stack -> prediction round-trip latency across processes on the real LCM bus: publishes a stack_t,\n"
              "waits for the matching prediction_t, one at a time; prints median and p99 per pile size, and the\n"
              "prediction's own compute time (from BL_TIMING) so transport and compute can be told apart.\n"
              "It starts its own bricklayer-prediction unless --no-spawn. LCM needs multicast routed; on a\n"
              "machine without a multicast route, or to keep the traffic off the network, run it inside\n"
              "tests/netns/run-in-netns:  tests/netns/run-in-netns build/bin/bricklayer-bench-roundtrip");
  flags.add("blocks", "25,60,200", "pile sizes, comma-separated");
  flags.add("count", "500", "round trips per size");
  flags.add("warmup", "20", "untimed round trips per size first");
  flags.add("annotator", "exact", "annotator of the spawned prediction (and of --verify)");
  flags.add("timeout-ms", "2000", "a round trip slower than this counts as lost");
  flags.add_bool("no-spawn", "use an already running bricklayer-prediction");
  flags.add_bool("verify", "check every answer byte for byte against the prediction logic and its knife-edge hysteresis in this process");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  if (!flags.parse(argc, argv)) return 0;
  const auto sizes = parse_sizes(flags.get("blocks"));
  const int64_t count = flags.get_int("count"), warmup = flags.get_int("warmup");
  if (count < 1 || warmup < 0) throw FlagError("--count must be >= 1 and --warmup >= 0");
  const auto timeout = std::chrono::milliseconds(flags.get_int("timeout-ms"));
  std::string url = resolve_lcm_url(flags.get("lcm-url"));
  check_lcm_url(url);

  prediction::PredictionConfig config;
  config.annotator = flags.get("annotator");
  prediction::PredictionLogic logic(config);
  RoundTrip client(url);

  launcher::Process server;
  if (!flags.get_bool("no-spawn")) {
    std::error_code ec;
    auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
    std::string exe = (self.parent_path() / "bricklayer-prediction").string();
    launcher::SpawnOptions opts;
    opts.env = {"LCM_DEFAULT_URL=" + url};
    server = launcher::Process::spawn({exe, "--annotator", config.annotator, "--log-level", "warn"}, opts);
  }
  if (!client.wait_for_prediction(server.started() ? server.pid() : 0, std::chrono::seconds(10)))
    throw std::runtime_error("no bricklayer-prediction heartbeat within 10 s on " + url);

  std::printf("stack -> prediction round trip across processes (%s, annotator %s, %lld per size)\n", url.c_str(),
              config.annotator.c_str(), static_cast<long long>(count));
  std::printf("%7s %10s %10s %10s %10s %16s %6s %10s\n", "blocks", "median_ms", "p99_ms", "min_ms", "max_ms",
              "predict_med_ms", "lost", "mismatch");
  const bool verify = flags.get_bool("verify");
  prediction::VerdictHysteresis hysteresis;  // the process's, for --verify
  int64_t frame = 1;
  bool all_ok = true;
  for (int n : sizes) {
    std::vector<double> latency, compute;
    int64_t lost = 0, mismatches = 0;
    for (int64_t i = 0; i < warmup + count; ++i, ++frame) {
      stack_t s = prediction::sample_stack(n, static_cast<uint32_t>(frame), 1'000'000 + frame, frame);
      double lat = 0, pred = 0;
      auto bytes = client.ask(s, timeout, lat, pred);
      // The process shows a verdict through the knife-edge hysteresis, which carries from one stack to
      // the next: the expected answer goes through one too, fed every stack the process was sent (the
      // warmup ones included).
      std::vector<uint8_t> expected;
      if (verify) {
        prediction_t answer = logic.answer(s);
        if (answer.status == prediction_t::STATUS_OK) prediction::show(answer, hysteresis.update(answer));
        expected = runtime::encode(answer);
      }
      if (i < warmup) continue;
      if (bytes.empty()) {
        ++lost;
        continue;
      }
      latency.push_back(lat / 1000.0);
      if (pred >= 0) compute.push_back(pred / 1000.0);
      if (verify && expected != bytes) ++mismatches;
    }
    std::printf("%7d %10.3f %10.3f %10.3f %10.3f %16.3f %6lld %10s\n", n, percentile(latency, 0.5),
                percentile(latency, 0.99), latency.empty() ? 0 : *std::min_element(latency.begin(), latency.end()),
                latency.empty() ? 0 : *std::max_element(latency.begin(), latency.end()), percentile(compute, 0.5),
                static_cast<long long>(lost),
                verify ? std::to_string(mismatches).c_str() : "-");
    std::fflush(stdout);
    all_ok = all_ok && lost == 0 && mismatches == 0;
  }
  if (server.started()) server.stop(std::chrono::seconds(3));
  return all_ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-bench-roundtrip", &Main, argc, argv); }
