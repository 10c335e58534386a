// bricklayer-projection: the augmented-reality display behind the board.
//
// Subscribes: BL_STACK (stack_t), BL_PREDICTION (prediction_t), BL_CALIBRATION (calibration_t),
//             BL_COMMAND (command_t), BL_HINT (hint_t), BL_PREVIEW (collapse_preview_t).
// Publishes:  BL_ROUND (round_t), BL_PROJECTOR (projector_state_t), BL_COMMAND (REQUEST_HINT on key H),
//             BL_TIMING (timing_t), BL_HEARTBEAT (heartbeat_t).
// Keys: S start round, R reset round, H request a hint, P snapshot, Esc/Q quit.
#include <cstdlib>

#include "bricklayer/common/flags.h"
#include "bricklayer/common/lcm_url.h"
#include "bricklayer/common/log.h"
#include "bricklayer/board/board_geometry.h"
#include "bricklayer/projection/projection_app.h"

namespace {

#ifndef BRICKLAYER_DEFAULT_BEST_OVERHANG
#define BRICKLAYER_DEFAULT_BEST_OVERHANG ""
#endif

int Main(int argc, char** argv) {
  using namespace bricklayer;
  Flags flags("bricklayer-projection",
              "Lights every block from behind the board (blue stable, red cause, magenta moving), shows score,\n"
              "MAX, round timer and a miniature of the pile, beeps when a red block appears, and shows\n"
              "calibration patterns on command. Rounds start by themselves when blocks appear on an empty board\n"
              "and end after --round-seconds or when the board stays empty. Keys: S start, R reset, H hint,\n"
              "P snapshot, Esc/Q quit.");
  flags.add("lcm-url", "", "LCM URL (default: $LCM_DEFAULT_URL, else host-only udpm ttl=0)");
  flags.add("log-level", "info", "debug, info, warn or error");
  flags.add("display", "", "borderless fullscreen on display index i (0 = first)");
  flags.add_bool("window", "a plain window (development)");
  flags.add_bool("headless", "no screen: SDL's offscreen driver (use --snapshot-dir to see the frames)");
  flags.add("width", std::to_string(kDefaultProjectorWidth), "projector width, pixels");
  flags.add("height", std::to_string(kDefaultProjectorHeight), "projector height, pixels");
  flags.add("snapshot-dir", "", "folder for PNG snapshots (latest.png, snapshot-NNNN.png on key P / command SNAPSHOT)");
  flags.add("snapshot-every", "0", "seconds between periodic snapshots into latest.png (0 = only on request)");
  flags.add("round-seconds", "180", "round length, seconds");
  flags.add("round-start-hold", "2", "blocks on a board seen empty this long start a round by themselves, seconds");
  flags.add("round-arm-empty", "1", "the board must be seen empty this long before blocks start the next round, seconds");
  flags.add("round-end-empty", "20", "a round ends early when the board stays empty this long, seconds");
  flags.add_bool("no-auto-start", "rounds start only on key S or START_ROUND");
  flags.add("rounds-file", "", "the round book: history and the day's best, kept across restarts (\"\" = not kept)");
  flags.add("stale-seconds", "3", "no stacks (or no predictions) this long: the board says so instead of a frozen verdict (0 = never)");
  flags.add("best-overhang", BRICKLAYER_DEFAULT_BEST_OVERHANG,
            "best overhang per block count, JSON {\"1\":0.5,...}; missing file = line not shown");
  flags.add("font", projection::kDefaultFontPath, "TrueType font for the text");
  flags.add("state-width", "256", "width of the game image in projector_state_t, pixels (patterns: full size)");
  flags.add("state-hz", "15", "at most this many projector_state_t per second");
  flags.add("fps", "60", "display refresh when the platform does not pace it (vsync)");
  flags.add("renderer", "", "SDL render driver for --window/--display (\"\" = SDL's choice, software, opengl, ...)");
  flags.add_bool("no-vsync", "do not wait for the display's vertical sync");
  flags.add_bool("mute", "no beep");
  if (!flags.parse(argc, argv)) return 0;
  log::set_level(log::parse_level(flags.get("log-level")));

  projection::ProjectionOptions options;
  options.lcm_url = resolve_lcm_url(flags.get("lcm-url"));
  try {
    check_lcm_url(options.lcm_url);
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
  const int modes = (flags.was_set("display") ? 1 : 0) + (flags.get_bool("window") ? 1 : 0) +
                    (flags.get_bool("headless") ? 1 : 0);
  if (modes > 1) throw FlagError("choose one of --display i, --window and --headless");
  if (flags.get_bool("headless")) {
    options.display.mode = projection::DisplayMode::kHeadless;
  } else if (flags.get_bool("window")) {
    options.display.mode = projection::DisplayMode::kWindow;
  } else {
    options.display.mode = projection::DisplayMode::kFullscreen;
    options.display.display_index = flags.was_set("display") ? static_cast<int>(flags.get_int("display")) : 0;
  }
  options.display.width = static_cast<int>(flags.get_int("width"));
  options.display.height = static_cast<int>(flags.get_int("height"));
  options.display.vsync = !flags.get_bool("no-vsync");
  options.display.render_driver = flags.get("renderer");
  options.snapshot_dir = flags.get("snapshot-dir");
  options.snapshot_every_s = flags.get_double("snapshot-every");
  const double round_seconds = flags.get_double("round-seconds");
  if (round_seconds <= 0 || round_seconds > 86400) throw FlagError("--round-seconds must be in (0, 86400]");
  options.rounds.duration_us = static_cast<int64_t>(round_seconds * 1e6);
  auto hold = [&flags](const char* name) {
    const double s = flags.get_double(name);
    if (!(s >= 0 && s <= 3600)) throw FlagError(std::string("--") + name + " must be in [0, 3600]");
    return static_cast<int64_t>(s * 1e6);
  };
  options.rounds.start_hold_us = hold("round-start-hold");
  options.rounds.arm_empty_us = hold("round-arm-empty");
  options.rounds.end_empty_us = hold("round-end-empty");
  options.rounds.auto_start = !flags.get_bool("no-auto-start");
  options.rounds_file = flags.get("rounds-file");
  options.stale_after_s = flags.get_double("stale-seconds");
  if (!(options.stale_after_s >= 0 && options.stale_after_s <= 3600)) throw FlagError("--stale-seconds must be in [0, 3600]");
  options.best_overhang_path = flags.get("best-overhang");
  options.font_path = flags.get("font");
  options.state_width = static_cast<int>(flags.get_int("state-width"));
  options.state_max_hz = flags.get_double("state-hz");
  options.fps = static_cast<int>(flags.get_int("fps"));
  options.mute = flags.get_bool("mute");
  try {
    projection::ProjectionApp app(options);
    return app.run();
  } catch (const std::invalid_argument& e) {
    throw FlagError(e.what());
  }
}

}  // namespace

int main(int argc, char** argv) { return bricklayer::run_main("bricklayer-projection", &Main, argc, argv); }
