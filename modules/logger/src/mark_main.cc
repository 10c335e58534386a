// bricklayer-mark: the operator marks this moment ("a visitor says the red block was wrong"). The
// logger keeps every camera frame around it (--full-rate-before-s / --full-rate-after-s) and lists it in
// the recording's index, where bricklayer-replay --video --from finds it.
//
// Publishes: BL_COMMAND (command_t MARK_MOMENT, argument = the note). Listens to BL_HEARTBEAT to say
// whether a logger counted it. Exit code 0 once a logger counted the mark, 1 when none did within
// --wait-s, 2 on bad usage.
#include <chrono>
#include <ctime>
#include <iostream>
#include <optional>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/lcm_bus.h"

namespace {
using namespace bricklayer;

std::optional<double> moments_of(const heartbeat_t& hb) {
  for (size_t i = 0; i < hb.value_names.size() && i < hb.values.size(); ++i)
    if (hb.value_names[i] == "moments") return hb.values[i];
  return std::nullopt;
}

int Main(int argc, char** argv) {
  Flags flags("bricklayer-mark",
              "Marks this moment in the exhibit's recording: the logger keeps full-rate camera frames around it\n"
              "and lists it (with NOTE) in the recording's index.");
  flags.add_positional("NOTE", "what happened (\"visitor: the red block looked wrong\"); may be empty");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only)");
  flags.add("wait-s", "3", "how long to wait for a logger to count the mark");
  if (!flags.parse(argc, argv)) return 0;
  const std::string url = resolve_lcm_url(flags.get("lcm-url"));
  check_lcm_url(url);
  const double wait_s = flags.get_double("wait-s");
  if (!(wait_s >= 0 && wait_s <= 600)) throw FlagError("--wait-s must be in [0, 600]");

  runtime::LcmBus bus(url, runtime::LcmBusOptions{""});
  std::optional<double> before, after;
  bus.subscribe(channel(kHeartbeatChannel), runtime::QueuePolicy::keep(1000), [&](const runtime::Received& r) {
    const auto hb = runtime::decode<heartbeat_t>(r.data, r.size);
    if (!hb || hb->module != "logger") return;
    const auto m = moments_of(*hb);
    if (!m) return;
    if (!before) before = *m;
    else if (*m > *before) after = *m;
  });
  command_t c{};
  c.utime = bus.now_utime();
  c.command = command_t::MARK_MOMENT;
  c.sequence = c.utime;
  c.argument = flags.positional().empty() ? "" : flags.positional()[0];
  // Heard the logger's count before marking, so its increase is ours (a heartbeat a second).
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  while (!before && std::chrono::steady_clock::now() < until) bus.handle(50);
  const auto bytes = runtime::encode(c);
  if (!bus.publish(channel(kCommandChannel), bytes.data(), bytes.size()))
    throw std::runtime_error("the bus refused the mark: " + bus.problem());
  std::time_t t = static_cast<std::time_t>(c.utime / 1000000);
  std::tm tm{};
  localtime_r(&t, &tm);
  char when[32];
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M:%S", &tm);
  while (!after && std::chrono::steady_clock::now() < until) bus.handle(50);
  if (after) {
    std::cout << "marked " << when << " (utime " << c.utime << "); the logger counted it\n";
    return 0;
  }
  std::cout << "marked " << when << " (utime " << c.utime << "), but no logger counted it within " << wait_s
            << " s (is the exhibit recording? " << (before ? "a logger was heard" : "no logger heard") << ")\n";
  return 1;
}
}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-mark", &Main, argc, argv); }
