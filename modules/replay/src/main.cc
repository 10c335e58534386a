// bricklayer-replay: feeds a recorded LCM log through a module's logic in-process (no network, as fast
// as possible) and, with --check, compares every output with the one recorded in the log.
//
// Subscribes: nothing (reads the log file with lcm::LogFile). Publishes: nothing.
// Exit code: 0 when every compared output is byte-identical, 1 on any mismatch, 2 on bad usage.
#include <chrono>
#include <iostream>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/log.h"
#include "bricklayer/replay/prediction_replay.h"
#include "bricklayer/replay/replay.h"

namespace {

using namespace bricklayer;

int Main(int argc, char** argv) {
  Flags flags("bricklayer-replay",
              "Replays an LCM log (recorded by lcm-logger or launch/bricklayer) through a module's logic,\n"
              "in-process and as fast as possible. With --check every output is compared byte for byte with\n"
              "the one recorded for the same input (channel + utime + frame_number); each mismatch is printed\n"
              "and the exit code is 1 on any. The last line is \"N compared, M mismatches (...)\".");
  flags.add_positional("LOG", "an LCM log file");
  flags.add("module", "prediction", "whose logic to replay (prediction)");
  flags.add_bool("check", "compare every output with the recorded one; exit 1 on any mismatch");
  flags.add("annotator", "", "prediction: annotator (default: the one recorded in the log, else exact)");
  flags.add("solver", "", "prediction: LP backend (default: the one recorded in the log, else clp)");
  flags.add("max-blocks", "1000", "prediction: the live process's --max-blocks");
  flags.add("position-tolerance", "", "prediction: block lengths (default: the one recorded in the log, else 0.005)");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_module("replay");
  log::set_level(log::parse_level(flags.get("log-level")));
  if (flags.get("module") != "prediction")
    throw FlagError("--module '" + flags.get("module") + "' has no replay yet (available: prediction)");
  int64_t max_blocks = flags.get_int("max-blocks");
  if (max_blocks < 1) throw FlagError("--max-blocks must be at least 1");

  std::unique_ptr<replay::PredictionReplay> module;
  try {
    std::optional<double> tolerance;
    if (!flags.get("position-tolerance").empty()) tolerance = flags.get_double("position-tolerance");
    module = std::make_unique<replay::PredictionReplay>(flags.get("annotator"), flags.get("solver"),
                                                        static_cast<size_t>(max_blocks), tolerance);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());  // names the bad --annotator / --solver / --position-tolerance
  }
  auto t0 = std::chrono::steady_clock::now();
  replay::ReplayReport report = replay::replay_log(flags.positional()[0], *module, flags.get_bool("check"), std::cout);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cerr << "replay: module " << module->name() << ", annotator " << module->config().annotator << ", solver "
            << module->config().solver << ", position tolerance " << module->config().position_tolerance << ", "
            << report.inputs << " inputs in " << seconds << " s\n";
  std::cout << report.summary() << std::endl;
  return report.ok() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-replay", &Main, argc, argv); }
