// bricklayer-prediction: the collapse prediction as a process on the bus.
//
// Subscribes: BL_STACK (stack_t), newest wins: a stack that arrives while one is waiting replaces it
//             (counted as dropped). Messages larger than --max-blocks allows, malformed bytes and
//             other types are counted errors.
// Publishes:  BL_PREDICTION (prediction_t) for every stack processed, carrying the stack's utime and
//             frame_number; a pure function of that stack (PredictionLogic), so replays compare byte
//             for byte.
//             BL_TIMING (timing_t, stage "predict") with the run-to-run timing, kept out of prediction_t.
//             BL_HEARTBEAT (heartbeat_t) once a second with the counters.
#include <chrono>

#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/timing_t.hpp"

namespace {

using namespace bricklayer;

class PredictionProcess {
 public:
  PredictionProcess(const std::string& url, prediction::PredictionConfig config)
      : module_("prediction", url),
        logic_(std::move(config)),
        stack_channel_(channel(kStackChannel)),
        prediction_channel_(channel(kPredictionChannel)),
        timing_channel_(channel(kTimingChannel)),
        latest_(module_.counters()) {
    module_.subscribe<stack_t>(
        stack_channel_, [this](const stack_t& s) { HandleStack(s); },
        prediction::max_stack_message_bytes(logic_.config().max_blocks));
    log::info("annotator ", logic_.config().annotator, ", solver ", logic_.config().solver, ", max ",
              logic_.config().max_blocks, " blocks; listening on ", stack_channel_);
  }

  int Run() { return module_.run([this] { Tick(); }); }

 private:
  struct Input {
    stack_t stack;
    int64_t received_utime;
  };

  void HandleStack(const stack_t& s) { latest_.put(Input{s, wall_utime()}); }

  void Tick() {
    auto input = latest_.take();
    if (!input) return;
    auto t0 = std::chrono::steady_clock::now();
    prediction_t p = logic_.answer(input->stack);
    auto elapsed = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0);
    if (p.status == prediction_t::STATUS_INVALID_STACK || p.status == prediction_t::STATUS_SOLVER_ERROR) {
      ++module_.counters().errors;
      log::warn("frame ", p.frame_number, ": ", p.error);
    }
    module_.publish(prediction_channel_, p);
    timing_t t{};
    t.utime = p.utime;
    t.frame_number = p.frame_number;
    t.module = "prediction";
    t.stage = "predict";
    t.elapsed_us = elapsed.count();
    t.received_utime = input->received_utime;
    lcm_publish_timing(t);
    module_.set_value("last_predict_us", static_cast<double>(elapsed.count()));
  }

  // Timings are not outputs: not counted as published.
  void lcm_publish_timing(const timing_t& t) { module_.lcm().publish(timing_channel_, &t); }

  Module module_;  // owns the LCM handle; declared before everything that subscribes through it
  prediction::PredictionLogic logic_;
  std::string stack_channel_, prediction_channel_, timing_channel_;
  Latest<Input> latest_;
};

int Main(int argc, char** argv) {
  Flags flags("bricklayer-prediction",
              "Answers every stack_t on BL_STACK with a prediction_t on BL_PREDICTION (newest stack wins),\n"
              "timings on BL_TIMING, a heartbeat on BL_HEARTBEAT every second.");
  flags.add("annotator", "exact", "which blocks are red: exact (initial-acceleration causes), paper, balance");
  flags.add("solver", "clp", "LP backend of the core: clp or nlopt");
  flags.add("max-blocks", "1000", "larger stacks get STATUS_INVALID_STACK; larger messages are rejected");
  flags.add("position-tolerance", std::to_string(prediction::kMeasuredPositionTolerance),
            "block lengths a measured position may be off; contact intervals are widened by this (0 = exact)");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));
  prediction::PredictionConfig config;
  config.annotator = flags.get("annotator");
  config.solver = flags.get("solver");
  config.position_tolerance = flags.get_double("position-tolerance");
  int64_t max_blocks = flags.get_int("max-blocks");
  if (max_blocks < 1 || max_blocks > 100000) throw FlagError("--max-blocks must be between 1 and 100000");
  config.max_blocks = static_cast<size_t>(max_blocks);
  try {
    prediction::PredictionLogic check(config);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());  // names the bad --annotator / --solver / --max-blocks / --position-tolerance
  }
  std::string url = resolve_lcm_url(flags.get("lcm-url"));
  try {
    check_lcm_url(url);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  PredictionProcess process(url, config);
  return process.Run();
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-prediction", &Main, argc, argv); }
