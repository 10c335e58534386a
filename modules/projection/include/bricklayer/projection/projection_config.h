// bricklayer-projection's configuration, each field declared once (runtime/config.h): the flags, --help,
// the checks, the JSON recorded on BL_CONFIG and the launcher's profile check all read this.
#pragma once

#include <string>

#include "bricklayer/board/board_geometry.h"
#include "bricklayer/projection/game_renderer.h"
#include "bricklayer/runtime/config.h"

namespace bricklayer::projection {

// The planner's best-overhang table in the source tree (empty when built without one).
std::string default_best_overhang_path();

struct ProjectionConfig {
  std::string display;  // "" = display 0 unless --window or --headless
  bool window = false;
  bool headless = false;
  int width = kDefaultProjectorWidth;
  int height = kDefaultProjectorHeight;
  std::string snapshot_dir;
  double snapshot_every = 0;
  double round_seconds = 180;
  double round_start_hold = 2;
  double round_arm_empty = 1;
  double round_end_empty = 20;
  bool no_auto_start = false;
  std::string rounds_file;
  double stale_seconds = 3;
  std::string best_overhang = default_best_overhang_path();
  std::string font = kDefaultFontPath;
  int state_width = 256;
  double state_hz = 15;
  double status_image_every = 2;
  int status_image_width = 320;
  int fps = 60;
  std::string renderer;
  bool no_vsync = false;
  bool mute = false;
  std::string condition = "proposed";

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("display", display, "borderless fullscreen on display index i (\"\" = 0 unless --window or --headless)")
          .must([](const std::string& s) -> std::string {
            if (s.empty()) return "";
            for (char c : s)
              if (c < '0' || c > '9' || s.size() > 3) return "must be a display index (0, 1, ...), got '" + s + "'";
            return "";
          }));
    v(runtime::param("window", window, "a plain window (development)"));
    v(runtime::param("headless", headless, "no screen: SDL's offscreen driver (use --snapshot-dir to see the frames)"));
    v(runtime::param("width", width, "projector width, pixels").range(16, 16384));
    v(runtime::param("height", height, "projector height, pixels").range(16, 16384));
    v(runtime::param("snapshot-dir", snapshot_dir,
                     "folder for PNG snapshots (latest.png, snapshot-NNNN.png on key P / command SNAPSHOT)"));
    v(runtime::param("snapshot-every", snapshot_every, "seconds between periodic snapshots into latest.png (0 = only on request)")
          .range(0, 86400));
    v(runtime::param("round-seconds", round_seconds, "round length, seconds").above_up_to(0, 86400));
    v(runtime::param("round-start-hold", round_start_hold,
                     "blocks on a board seen empty this long start a round by themselves, seconds").range(0, 3600));
    v(runtime::param("round-arm-empty", round_arm_empty,
                     "the board must be seen empty this long before blocks start the next round, seconds").range(0, 3600));
    v(runtime::param("round-end-empty", round_end_empty, "a round ends early when the board stays empty this long, seconds")
          .range(0, 3600));
    v(runtime::param("no-auto-start", no_auto_start, "rounds start only on key S or START_ROUND"));
    v(runtime::param("rounds-file", rounds_file, "the round book: history and the day's best, kept across restarts (\"\" = not kept)"));
    v(runtime::param("stale-seconds", stale_seconds,
                     "no stacks (or no predictions) this long: the board says so instead of a frozen verdict (0 = never)")
          .range(0, 3600));
    v(runtime::param("best-overhang", best_overhang,
                     "best overhang per block count, JSON {\"1\":0.5,...}; missing file = line not shown"));
    v(runtime::param("font", font, "TrueType font for the text").existing_file());
    v(runtime::param("state-width", state_width, "width of the game image in projector_state_t, pixels (patterns: full size)")
          .range(16, 16384));
    v(runtime::param("state-hz", state_hz, "at most this many projector_state_t per second").above_up_to(0, 1000));
    v(runtime::param("status-image-every", status_image_every,
                     "seconds (runtime clock) between the small JPEGs of what is projected on BL_PROJECTOR_IMAGE, "
                     "for the operator's status page (0 = none)")
          .range(0, 3600));
    v(runtime::param("status-image-width", status_image_width, "width of the status page's projector JPEG, pixels")
          .range(16, 4096));
    v(runtime::param("fps", fps, "display refresh when the platform does not pace it (vsync)").range(1, 1000));
    v(runtime::param("renderer", renderer, "SDL render driver for --window/--display (\"\" = SDL's choice, software, opengl, ...)"));
    v(runtime::param("no-vsync", no_vsync, "do not wait for the display's vertical sync"));
    v(runtime::param("mute", mute, "no beep"));
    v(runtime::param("condition", condition,
                     "display condition at start (the seed paper's study): blue (always blue), red (all red while the "
                     "pile falls), proposed (the blocks that start the collapse red); SET_CONDITION and key C change it")
          .one_of({"blue", "red", "proposed"}));
  }
};

}  // namespace bricklayer::projection
