#include "bricklayer/replay/module_registry.h"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "bricklayer/common/channels.h"
#include "bricklayer/planner/planner_node.h"
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/vision/vision_node.h"
#ifdef BRICKLAYER_REPLAY_PROJECTION
#include "bricklayer/projection/projection_node.h"
#endif
#ifdef BRICKLAYER_REPLAY_CALIBRATE
#include "bricklayer/board/calibration_file.h"
#include "bricklayer/calibration/calibrate_node.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/runtime/codec.h"
#endif

namespace bricklayer::replay {
namespace {

#ifdef BRICKLAYER_REPLAY_PROJECTION
AdapterOptions<projection::ProjectionConfig> projection_options() {
  AdapterOptions<projection::ProjectionConfig> o;
  // The count of frames drawn: one per display refresh, so it says how often the live loop ran (every
  // arrival and every 1/fps s), which a replay's loop does not repeat. The picture itself is compared.
  o.ignored = {"projector_state_t.image.frame_number"};
  // round_t, projector_state_t and the status JPEG are stamped with the tick that sent them (a
  // timer: once a second, at most --state-hz, every --status-image-every s).
  o.ticks_at_outputs = true;
  // Paired by nearest time (a log recorded live on LCM), these depend on when the tick fell: the stamps,
  // and the round's time left read at the tick. The status JPEG's frame_number counts the pictures sent
  // on the runtime clock's schedule from the node's start, and is compared.
  o.tick_fields = {"round_t.utime", "round_t.remaining_ms", "projector_state_t.utime", "projector_state_t.image.utime",
                   "image_t.utime"};
  // What it reads (projection_node.h): a pair by nearest time with one of these between its stamps
  // drew other inputs, and is not compared.
  o.tick_inputs = {channel(kStackChannel),        channel(kPredictionChannel),   channel(kCalibrationChannel),
                   channel(kHintChannel),         channel(kPreviewChannel),      channel(kStudySessionChannel),
                   channel(kStudyProblemChannel), channel(kCommandChannel)};
  o.replay_settings = [](projection::ProjectionConfig& c, const BuildContext&) {
    std::vector<std::string> notes;
    // No screen and no sound in a replay: SDL's offscreen video driver with the software renderer
    // (deterministic pixels). A live screen redraws on every refresh, a headless display only on a
    // change: a window on the offscreen driver keeps the live redraws.
    if (!c.headless) {
      setenv("SDL_VIDEODRIVER", "offscreen", 1);
      c.window = true;
      c.display.clear();
      c.renderer = "software";
      c.no_vsync = true;
      notes.push_back("drawn in a window of SDL's offscreen driver with the software renderer (live: a screen)");
    }
    if (!c.mute) {
      c.mute = true;
      notes.push_back("muted");
    }
    // Never the live round book or snapshot folder: a replay writes nothing of the exhibit's.
    if (!c.rounds_file.empty()) {
      notes.push_back("without its round book " + c.rounds_file +
                      " (the replay starts from an empty one: a day's best restored live is not)");
      c.rounds_file.clear();
    }
    // A log recorded from another checkout names its best-overhang table there: this build's own.
    std::error_code ec;
    if (!c.best_overhang.empty() && !std::filesystem::exists(c.best_overhang, ec) &&
        std::filesystem::exists(projection::default_best_overhang_path(), ec)) {
      notes.push_back("best-overhang table " + c.best_overhang + " is not here: this build's " +
                      projection::default_best_overhang_path());
      c.best_overhang = projection::default_best_overhang_path();
    }
    if (!c.snapshot_dir.empty()) {
      notes.push_back("no snapshots (live into " + c.snapshot_dir + ")");
      c.snapshot_dir.clear();
      c.snapshot_every = 0;
    }
    return notes;
  };
  return o;
}
#endif

#ifdef BRICKLAYER_REPLAY_CALIBRATE
AdapterOptions<calibration::CalibrateConfig> calibrate_options() {
  AdapterOptions<calibration::CalibrateConfig> o;
  // BL_COMMAND is shared: the calibration's pattern commands say who sent them.
  o.owns = [](const std::string& ch, const std::vector<uint8_t>& bytes) {
    if (ch != channel(kCommandChannel)) return true;
    const auto c = runtime::decode<command_t>(bytes);
    return c && c->argument == "bricklayer-calibrate";
  };
  // --serve republishes on a timer; a calibration run sends a pattern on the tick a frame arrived.
  o.ticks_at_outputs = true;
  // Paired by nearest time (a log recorded live on LCM): the stamps, and the pattern commands' sequence
  // (the clock at its first command, then counting: next_sequence()).
  o.tick_fields = {"calibration_t.utime", "command_t.utime", "command_t.sequence"};
  o.decodes_frames = true;
  o.replay_settings = [](calibration::CalibrateConfig& c, const BuildContext& context) {
    std::vector<std::string> notes;
    const std::string live = c.output;
    c.output = (std::filesystem::path(context.scratch_dir) / "calibration.json").string();
    const bool loads = c.serve || c.self_check || c.scale_from_blocks;
    if (loads) {
      // The file it served live is not in the log; what it published first is.
      if (context.recorded_calibration.empty()) {
        notes.push_back("no calibration_t recorded in the range: it starts without " + live);
      } else if (const auto cal = runtime::decode<calibration_t>(context.recorded_calibration)) {
        board::save_calibration(c.output, *cal);
        notes.push_back("loads the first calibration recorded on " + channel(kCalibrationChannel) + " (live: " + live + ")");
      }
    } else {
      notes.push_back("writes its calibration into the replay's scratch folder (live: " + live + ")");
    }
    c.write_default = false;
    return notes;
  };
  return o;
}
#endif

}  // namespace

const std::vector<ModuleAdapter>& replayable_modules() {
  static const std::vector<ModuleAdapter> modules = [] {
    std::vector<ModuleAdapter> m;
    AdapterOptions<vision::VisionConfig> vision;
    vision.decodes_frames = true;
    m.push_back(node_adapter<vision::VisionNode>("vision", {channel(kStackChannel)}, vision));
    m.push_back(node_adapter<prediction::PredictionNode>("prediction", {channel(kPredictionChannel)}));
    m.push_back(node_adapter<planner::PlannerNode>("planner", {channel(kPreviewChannel), channel(kHintChannel)}));
#ifdef BRICKLAYER_REPLAY_PROJECTION
    m.push_back(node_adapter<projection::ProjectionNode>(
        "projection", {channel(kRoundChannel), channel(kProjectorChannel), channel(kProjectorImageChannel)},
        projection_options()));
#endif
#ifdef BRICKLAYER_REPLAY_CALIBRATE
    m.push_back(node_adapter<calibration::CalibrateNode>(
        "calibrate", {channel(kCalibrationChannel), channel(kCommandChannel)}, calibrate_options()));
#endif
    return m;
  }();
  return modules;
}

std::string replayable_names() {
  std::string out;
  for (const auto& m : replayable_modules()) out += (out.empty() ? "" : ", ") + m.name;
  return out;
}

const ModuleAdapter& module_named(const std::string& name) {
  for (const auto& m : replayable_modules())
    if (m.name == name) return m;
  throw std::invalid_argument("no module '" + name + "' to replay in this build (available: " + replayable_names() + ")");
}

}  // namespace bricklayer::replay
