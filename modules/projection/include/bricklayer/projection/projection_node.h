// bricklayer-projection's node: the display, the rounds and the beep on the runtime (runtime/node.h),
// so the same node runs live (LcmBus), on the in-process rig and from a recorded log, and reads the
// time only from its bus's clock.
//
// Subscribes: BL_STACK (stack_t), BL_PREDICTION (prediction_t), BL_CALIBRATION (calibration_t),
//             BL_HINT (hint_t), BL_PREVIEW (collapse_preview_t), BL_STUDY_SESSION (study_session_t: its
//             instruction is shown while the session driver is heard), BL_STUDY_PROBLEM (study_problem_t:
//             a stabilise problem's pile drawn as outlines, a score problem's target, while current as
//             problem_outline.h says; a malformed one is a counted error): newest wins;
//             BL_COMMAND (command_t): every command counts (a queue of 1000); SET_CONDITION sets the
//             display condition (display_condition.h; a bad index is a counted error).
// Publishes:  BL_ROUND (round_t) on every change and once a second;
//             BL_PROJECTOR (projector_state_t) after every presented frame that changed, at most
//             --state-hz times a second: the presented image as PNG (game display downscaled to
//             --state-width, patterns at full projector size) and the sequence of the last pattern
//             command applied;
//             BL_PROJECTOR_IMAGE (image_t, source "projector"): what is presented, a JPEG
//             --status-image-width wide every --status-image-every seconds of the runtime clock (the
//             operator's status page shows it; small, so the logger records it at its own rate);
//             BL_COMMAND (command_t REQUEST_HINT) when H is pressed;
//             BL_STUDY_COMMAND (study_command_t DONE) when D is pressed (the subject says "done");
//             BL_TIMING (timing_t, stage "present"): prediction received -> frame presented (a real
//             stopwatch: a run-to-run figure);
//             BL_HEARTBEAT once a second (values frames, present_p50_ms, calibrated, day_best,
//             rounds_today, condition; status "camera not seeing: no stacks for 7 s" while an input is stale).
// Rounds run themselves (round_referee.h) and are kept in the round book (round_book.h) when
// --rounds-file is given; every round_t carries the display condition. Keys: S start, R reset, H hint,
// C next display condition, D done (study), P snapshot, Esc/Q quit.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/calibration_t.hpp"
#include "bricklayer/command_t.hpp"
#include "bricklayer/projection/beeper.h"
#include "bricklayer/projection/best_overhang.h"
#include "bricklayer/projection/display_condition.h"
#include "bricklayer/projection/display.h"
#include "bricklayer/projection/game_renderer.h"
#include "bricklayer/projection/input_watch.h"
#include "bricklayer/projection/problem_outline.h"
#include "bricklayer/projection/projection_config.h"
#include "bricklayer/projection/red_debounce.h"
#include "bricklayer/projection/round_referee.h"
#include "bricklayer/projection/scene.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/study_session_t.hpp"

namespace bricklayer::projection {

// The image a SHOW_PATTERN command asks for, BGR at projector size (calibration's renderer).
// Throws std::invalid_argument for a pattern it cannot draw.
cv::Mat render_command_pattern(const command_t& command, int width, int height);

class ProjectionNode final : public runtime::Node {
 public:
  using Config = ProjectionConfig;
  static constexpr const char* kProgram = "bricklayer-projection";
  static constexpr const char* kSummary =
      "Lights every block from behind the board (blue stable, red cause, magenta moving), shows score,\n"
      "MAX, round timer and a miniature of the pile, beeps when a red block appears, and shows\n"
      "calibration patterns on command. Rounds start by themselves when blocks appear on an empty board\n"
      "and end after --round-seconds or when the board stays empty; the board says \"camera not seeing\"\n"
      "or \"waiting for the other machine\" instead of a frozen verdict. Display conditions of the seed paper's\n"
      "study (--condition, command SET_CONDITION, key C): blue (always blue), red (all red while the pile\n"
      "falls), proposed (the causes red, the default); a study session's instruction is shown, and the problem\n"
      "being solved: a pile to build as outlines, a score to reach with the time left. Keys: S start,\n"
      "R reset, H hint, C next condition, D done (study), P snapshot, Esc/Q quit.";

  // Rules across fields (one display mode, state width within the image, snapshots need a folder).
  static void check(const Config& config);

  // Throws std::invalid_argument for a bad configuration, std::runtime_error when the display, the
  // font or the snapshot folder cannot be set up.
  ProjectionNode(const Config& config, runtime::Bus& bus);
  ~ProjectionNode() override;

  bool quit_requested() const { return quit_; }
  Display& display() { return *display_; }
  // Where the last game frame put its parts (text bounds, the problem's outlines).
  const Layout& layout() const { return renderer_->layout(); }
  const Scene& scene() const { return scene_; }
  const RoundReferee& round() const { return round_; }
  InputProblem input_problem() const { return watch_.problem(now()); }
  const Beeper* beeper() const { return beeper_.get(); }
  // Prediction received -> frame presented, microseconds (stopwatch), one per presented prediction.
  const std::vector<int64_t>& present_latencies_us() const { return latencies_us_; }
  int64_t frames_presented() const { return frames_presented_; }
  bool pattern_shown() const { return pattern_.has_value(); }
  DisplayCondition condition() const { return condition_; }
  // The study session's instruction being shown ("" = none: no session heard for kStudySessionHeardUs).
  std::string instruction() const;
  // How long the study session's instruction stays after its driver's last message: the driver publishes
  // once a second, so three missed messages mean it has gone.
  static constexpr int64_t kStudySessionHeardUs = 3'000'000;
  // The study problem shown now (problem_outline.h): outlines, a target, or nothing.
  ProblemView problem_view() const;
  // Study problems refused as malformed (each also a counted error).
  int64_t problems_rejected() const { return problems_rejected_; }

 protected:
  void tick() override;
  void before_heartbeat() override;

 private:
  void on_stack(const stack_t& s);
  void on_prediction(const prediction_t& p);
  void on_calibration(const calibration_t& c);
  void apply_command(const command_t& command);
  void handle_events();
  void advance_round();
  void draw_and_present();
  void capture_if_due();
  void publish_status_image(const cv::Mat& frame, int64_t t);  // BL_PROJECTOR_IMAGE, the status page's JPEG
  void publish_round();
  void request_hint();
  void set_condition(DisplayCondition condition, const std::string& by);
  void on_study_session(const study_session_t& s);
  void on_study_problem(const study_problem_t& p);
  const study_session_t* heard_session() const;  // the newest session, if heard within kStudySessionHeardUs
  void send_done();
  bool awaiting_prediction() const;
  void save_rounds();
  void restore_rounds();

  Config config_;
  std::unique_ptr<Display> display_;
  std::unique_ptr<GameRenderer> renderer_;
  std::unique_ptr<Beeper> beeper_;
  BestOverhang best_overhang_;
  std::string stack_channel_, prediction_channel_, command_channel_, round_channel_, projector_channel_,
      timing_channel_, study_command_channel_;

  std::optional<calibration_t> applied_calibration_;  // the last one taken (applied or rejected)
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
  std::optional<std::chrono::steady_clock::time_point> prediction_received_;  // awaiting its frame
  int64_t prediction_received_utime_ = 0;
  std::vector<int64_t> latencies_us_;
  int64_t frames_presented_ = 0;
  bool unpublished_frame_ = false;
  int64_t last_state_utime_ = -1;
  cv::Mat last_state_image_;
  int64_t last_state_sequence_ = -2;
  int last_state_mode_ = -1;
  bool snapshot_requested_ = false;
  int64_t next_snapshot_utime_ = 0;
  int snapshot_count_ = 0;
  int64_t next_status_image_utime_ = INT64_MAX;  // the next projector JPEG for the status page (runtime clock)
  int64_t status_images_ = 0;
  int64_t next_round_publish_utime_ = 0;
  int64_t hint_sequence_ = 0;
  int64_t stack_arrived_utime_ = -1;           // when the drawn stack arrived
  int64_t last_prediction_utime_ = INT64_MIN;  // when the last prediction arrived
  int64_t start_utime_ = 0;
  DisplayCondition condition_ = DisplayCondition::kProposed;
  std::optional<study_session_t> study_session_;  // the newest heard
  int64_t study_session_utime_ = INT64_MIN;        // when it arrived (bus clock)
  std::optional<int8_t> study_condition_;          // the last session condition adopted
  std::string drawn_instruction_;
  ProblemOutline study_problem_;
  ProblemView drawn_problem_;
  int64_t problems_rejected_ = 0;
  int64_t study_command_sequence_ = 0;
};

}  // namespace bricklayer::projection
