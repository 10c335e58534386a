// bricklayer-projection's process: the bus, the display, the round and the beep, in one loop that
// never blocks on LCM (poll on LCM's file descriptor with a timeout up to the next display refresh,
// then handleTimeout(0) until drained).
//
// Subscribes: BL_STACK (stack_t), BL_PREDICTION (prediction_t), BL_CALIBRATION (calibration_t),
//             BL_COMMAND (command_t), BL_HINT (hint_t), BL_PREVIEW (collapse_preview_t).
// Publishes:  BL_ROUND (round_t) on every change and once a second;
//             BL_PROJECTOR (projector_state_t) after every presented frame that changed, at most
//             --state-hz times a second: the presented image as PNG (game display downscaled to
//             --state-width, patterns at full projector size) and the sequence of the last pattern
//             command applied;
//             BL_COMMAND (command_t REQUEST_HINT) when H is pressed;
//             BL_TIMING (timing_t, stage "present") prediction received -> frame presented;
//             BL_HEARTBEAT once a second (values day_best, rounds_today; status says a stale input).
// Rounds run themselves (round_referee.h) and are kept in the round book (round_book.h) when
// --rounds-file is given; time is this process's bus clock (the wall clock on LCM, as LcmBus's).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/calibration_t.hpp"
#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/common/module.h"
#include "bricklayer/hint_t.hpp"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/projection/beeper.h"
#include "bricklayer/projection/best_overhang.h"
#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/projection/display.h"
#include "bricklayer/projection/game_renderer.h"
#include "bricklayer/projection/red_debounce.h"
#include "bricklayer/projection/input_watch.h"
#include "bricklayer/projection/round_referee.h"
#include "bricklayer/projection/scene.h"
#include "bricklayer/stack_t.hpp"

namespace bricklayer::projection {

struct ProjectionOptions {
  std::string lcm_url;                 // resolved already
  DisplayOptions display;
  std::string font_path = kDefaultFontPath;
  std::string best_overhang_path;      // "" = no table
  RoundRules rounds;                   // duration, start/end holds, auto start
  std::string rounds_file;             // the round book (history, day's best); "" = kept in memory only
  double stale_after_s = 3;            // no stacks / predictions this long: say so on the board (0 = never)
  std::string snapshot_dir;            // "" = no snapshots
  double snapshot_every_s = 0;         // 0 = only on request (key P, command SNAPSHOT)
  int state_width = 256;               // width of the game image in projector_state_t
  double state_max_hz = 15;
  int fps = 60;                        // display refresh when the platform does not pace it
  bool mute = false;
  ToneOptions tone;
  int64_t beep_hold_ms = 300;
  int64_t beep_rearm_ms = 1000;
};

// The image a SHOW_PATTERN command asks for, BGR at projector size (calibration's renderer).
// Throws std::invalid_argument for a pattern it cannot draw.
cv::Mat render_command_pattern(const command_t& command, int width, int height);

class ProjectionApp {
 public:
  // Throws std::runtime_error / std::invalid_argument on bad configuration (bus, display, font,
  // snapshot folder).
  explicit ProjectionApp(const ProjectionOptions& options);
  ~ProjectionApp();

  // Runs until SIGINT/SIGTERM, Esc/Q or the window is closed. Returns the exit code.
  int run();
  // One iteration: waits up to wait_ms for the bus, handles messages and SDL events, advances the
  // round and the beep, draws and presents when something changed (or at every refresh with a real
  // window), publishes what is due.
  void step(int wait_ms);
  bool quit_requested() const { return quit_; }

  Module& module() { return module_; }
  Display& display() { return *display_; }
  const Scene& scene() const { return scene_; }
  const RoundReferee& round() const { return round_; }
  InputProblem input_problem() const { return watch_.problem(clock_utime()); }
  const Beeper* beeper() const { return beeper_.get(); }
  // Prediction received -> frame presented, microseconds, one per presented prediction.
  const std::vector<int64_t>& present_latencies_us() const { return latencies_us_; }
  int64_t frames_presented() const { return frames_presented_; }
  bool pattern_shown() const { return pattern_.has_value(); }

 private:
  struct Stamped {
    int64_t received_us = 0;  // steady clock
    int64_t received_utime = 0;  // wall clock
  };
  void wait_for_bus(int wait_ms);
  void handle_events();
  void apply_inputs();
  void apply_command(const command_t& command);
  void tick();
  void draw_and_present();
  void capture_if_due();
  void publish_round();
  void save_rounds();
  void restore_rounds();
  // The bus clock: microseconds since the epoch (the live LCM bus's clock is the wall clock).
  int64_t clock_utime() const;
  void request_hint();
  bool awaiting_prediction() const;
  int64_t now_ms() const;
  int64_t now_us() const;

  ProjectionOptions options_;
  Module module_;
  std::unique_ptr<Display> display_;
  std::unique_ptr<GameRenderer> renderer_;
  std::unique_ptr<Beeper> beeper_;
  BestOverhang best_overhang_;

  Latest<stack_t> stack_in_;
  Latest<prediction_t> prediction_in_;
  Latest<calibration_t> calibration_in_;
  std::optional<calibration_t> applied_calibration_;  // the last one taken (applied or rejected)
  Latest<hint_t> hint_in_;
  Latest<collapse_preview_t> preview_in_;
  std::vector<command_t> commands_in_;  // every command counts: no newest-wins here
  Stamped prediction_stamp_{};

  Scene scene_;
  board::BoardToProjector mapping_;
  RoundReferee round_;
  InputWatch watch_;
  uint64_t saved_revision_ = 0;
  InputProblem shown_problem_ = InputProblem::kNone;
  RedDebounce debounce_;
  std::optional<cv::Mat> pattern_;
  int64_t pattern_sequence_ = -1;

  bool dirty_ = true;
  bool quit_ = false;
  std::optional<Stamped> pending_latency_;
  std::vector<int64_t> latencies_us_;
  int64_t frames_presented_ = 0;
  bool unpublished_frame_ = false;
  int64_t last_state_us_ = -1;
  cv::Mat last_state_image_;
  int64_t last_state_sequence_ = -2;
  int last_state_mode_ = -1;
  bool snapshot_requested_ = false;
  int64_t next_snapshot_ms_ = 0;
  int snapshot_count_ = 0;
  int64_t next_round_publish_ms_ = 0;
  int64_t next_heartbeat_ms_ = 0;
  int64_t next_refresh_ms_ = 0;
  int64_t hint_sequence_ = 0;
  int64_t stack_arrived_ms_ = -1;       // when the drawn stack arrived
  int64_t last_prediction_ms_ = -100000;  // when the last prediction arrived
  std::chrono::steady_clock::time_point started_;
};

}  // namespace bricklayer::projection
