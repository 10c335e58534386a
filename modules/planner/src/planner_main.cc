// bricklayer-planner: how the pile will fall and where the next block should go.
//
// Subscribes: BL_STACK (stack_t): the newest stacks are remembered (the last 16) to match predictions
//             against and to compute hints for; invalid stacks are counted errors.
//             BL_PREDICTION (prediction_t), newest wins: an unbalanced prediction whose stack was seen is
//             answered with a collapse preview; balanced ones need nothing.
//             BL_COMMAND (command_t): REQUEST_HINT asks for a hint for the newest stack (answered as soon as
//             a stack is known); other commands are ignored.
// Publishes:  BL_PREVIEW (collapse_preview_t) carrying the utime and frame_number of the stack it answers.
//             BL_HINT (hint_t) for the newest stack on each REQUEST_HINT.
//             BL_HEARTBEAT (heartbeat_t) once a second with the counters.
#include <chrono>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/common/module.h"
#include "bricklayer/planner/planner_logic.h"

namespace {

using namespace bricklayer;

class PlannerProcess {
 public:
  PlannerProcess(const std::string& url, planner::PlannerConfig config)
      : module_("planner", url),
        logic_(std::move(config)),
        stack_channel_(channel(kStackChannel)),
        prediction_channel_(channel(kPredictionChannel)),
        command_channel_(channel(kCommandChannel)),
        preview_channel_(channel(kPreviewChannel)),
        hint_channel_(channel(kHintChannel)),
        latest_prediction_(module_.counters()) {
    module_.subscribe<stack_t>(stack_channel_, [this](const stack_t& s) { HandleStack(s); });
    module_.subscribe<prediction_t>(prediction_channel_, [this](const prediction_t& p) { HandlePrediction(p); });
    module_.subscribe<command_t>(command_channel_, [this](const command_t& c) { HandleCommand(c); }, 1 << 16);
    log::info("listening on ", stack_channel_, ", ", prediction_channel_, ", ", command_channel_, "; margin ",
              logic_.config().hint.margin);
  }

  int Run() { return module_.run([this] { Tick(); }); }

 private:
  void HandleStack(const stack_t& s) {
    if (s.status != stack_t::STATUS_OK) return;  // nothing measured: nothing to plan
    try {
      logic_.on_stack(s);
    } catch (const std::exception& e) {
      ++module_.counters().errors;
      log::warn("stack frame ", s.frame_number, " ignored: ", e.what());
    }
  }
  void HandlePrediction(const prediction_t& p) { latest_prediction_.put(p); }
  void HandleCommand(const command_t& c) {
    if (c.command == command_t::REQUEST_HINT) hint_requested_ = true;
  }

  void Tick() {
    if (auto p = latest_prediction_.take()) {
      const auto t0 = std::chrono::steady_clock::now();
      try {
        if (auto preview = logic_.preview_for(*p)) {
          module_.publish(preview_channel_, *preview);
          module_.set_value("last_preview_ms", Ms(t0));
        }
      } catch (const std::exception& e) {
        ++module_.counters().errors;
        log::warn("preview for frame ", p->frame_number, " failed: ", e.what());
      }
    }
    if (hint_requested_) {
      const auto t0 = std::chrono::steady_clock::now();
      try {
        if (auto hint = logic_.hint_for_newest()) {
          hint_requested_ = false;
          module_.publish(hint_channel_, *hint);
          module_.set_value("last_hint_ms", Ms(t0));
        }
      } catch (const std::exception& e) {
        hint_requested_ = false;
        ++module_.counters().errors;
        log::warn("hint failed: ", e.what());
      }
    }
  }

  static double Ms(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  Module module_;  // owns the LCM handle; declared before everything that subscribes through it
  planner::PlannerLogic logic_;
  std::string stack_channel_, prediction_channel_, command_channel_, preview_channel_, hint_channel_;
  Latest<prediction_t> latest_prediction_;
  bool hint_requested_ = false;
};

int Main(int argc, char** argv) {
  Flags flags("bricklayer-planner",
              "Publishes a collapse preview (BL_PREVIEW) for every unbalanced prediction and a next-block hint\n"
              "(BL_HINT) for the newest stack on each REQUEST_HINT command.");
  flags.add("margin", "0.02", "hint safety margin, block lengths: suggested blocks stay balanced when shifted by +/- this");
  flags.add("max-added", "2", "rebalancing hints add at most this many blocks (1 or 2)");
  flags.add("preview-seconds", "0.7", "longest simulated collapse, seconds of real time");
  flags.add("max-blocks", "1000", "larger stacks are ignored (counted errors)");
  flags.add("lcm-url", "", "LCM URL (default: LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));
  planner::PlannerConfig config;
  config.hint.margin = flags.get_double("margin");
  if (!(config.hint.margin > 0 && config.hint.margin < 0.5)) throw FlagError("--margin must be in (0, 0.5)");
  const int64_t max_added = flags.get_int("max-added");
  if (max_added < 1 || max_added > 2) throw FlagError("--max-added must be 1 or 2");
  config.hint.max_added = static_cast<int>(max_added);
  const double seconds = flags.get_double("preview-seconds");
  if (!(seconds > 0 && seconds <= 10)) throw FlagError("--preview-seconds must be in (0, 10]");
  config.collapse.max_time = seconds / planner::seconds_per_time_unit();
  const int64_t max_blocks = flags.get_int("max-blocks");
  if (max_blocks < 1 || max_blocks > 100000) throw FlagError("--max-blocks must be between 1 and 100000");
  config.max_blocks = static_cast<size_t>(max_blocks);
  std::string url = resolve_lcm_url(flags.get("lcm-url"));
  try {
    check_lcm_url(url);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  PlannerProcess process(url, config);
  return process.Run();
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-planner", &Main, argc, argv); }
