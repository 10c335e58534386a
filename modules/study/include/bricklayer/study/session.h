// The study protocol of one subject, as a state machine fed with times and observations (no bus, no
// clock of its own: the session node feeds it, a test drives it directly, and a replay gets the same
// outputs from the same inputs).
//
//   WAITING --start--> TRIAL_1 -> PROBLEM_1 -> PROBLEM_2 -> PROBLEM_3 -> TRIAL_2 -> DONE
//
// Every step begins READY: the display asks the subject to clear the board, and the step runs once the
// board has been empty for clear_ms. A trial is a game of trial_ms; its score is the best score of a
// balanced pile during it. A stabilise problem is answered when the subject says done (done()), or by
// itself once a pile holding every given block has stood unchanged for settle_ms, or with the last pile
// seen when its time is up; the checker judges it. The score problem is answered when its goal has held
// (ScoreJudge) or its time is up. The experimenter can pause (the step's clock stops, observations are
// ignored), resume, repeat (the running step again from READY with the next attempt; in READY, the step
// before) and abort (the session ends, and a report leaves it out).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/core/stack.h"
#include "bricklayer/study/checker.h"
#include "bricklayer/study/problem.h"
#include "bricklayer/study/table.h"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_problem_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "bricklayer/study_trial_t.hpp"

namespace bricklayer::study {

struct SessionSetup {
  std::string session_id;
  std::string subject_id;
  Condition condition = Condition::kProposed;
  int64_t trial_ms = 120'000;  // each game (the seed paper's protocol: two minutes)
  int64_t clear_ms = 1'000;    // the board empty this long before a step runs
  int64_t settle_ms = 3'000;   // stabilise: a complete standing pile unchanged this long is the answer
};

// One verdict on the pile: the stack that was measured and the prediction that answered it.
struct Observation {
  int64_t utime = 0;
  bool valid = false;  // a measurement with a verdict (prediction status OK)
  core::Stack stack;   // as measured, any units
  bool balanced = false;
  int32_t score = 0;
};

// What the protocol asks the display to do, besides showing the session state.
enum class RoundCommand { kStart, kReset };

struct SessionOutputs {
  bool state_changed = false;  // publish the session state now
  std::vector<bricklayer::study_trial_t> trials;
  std::vector<bricklayer::study_answer_t> answers;
  std::vector<bricklayer::study_problem_t> problems;  // a problem step began running
  std::vector<RoundCommand> rounds;
};

class SessionProtocol {
 public:
  // The two stabilise problems' checkers (shared: computing a minimum takes a moment) and the score
  // problem. Throws std::invalid_argument when a problem is of the wrong kind or ids are empty.
  SessionProtocol(SessionSetup setup, std::shared_ptr<const StabiliseChecker> problem1,
                  std::shared_ptr<const StabiliseChecker> problem2, Problem problem3);

  // The experimenter's and subject's commands; false (and nothing changes) when not applicable now.
  bool start(int64_t utime);
  bool pause(int64_t utime);
  bool resume(int64_t utime);
  bool repeat(int64_t utime);
  bool abort(int64_t utime);
  bool done(int64_t utime);  // the subject says done (stabilise problems)

  void observe(const Observation& observation);
  void tick(int64_t utime);  // time limits and holds; call often (10 Hz is plenty)

  SessionOutputs take_outputs();

  bricklayer::study_session_t state(int64_t utime) const;
  // The problem of the current step while it is ready, running or paused.
  std::optional<bricklayer::study_problem_t> current_problem(int64_t utime) const;
  int8_t step() const { return step_; }
  int8_t step_state() const { return state_; }
  bool finished() const;  // DONE or aborted

 private:
  void begin_step(int8_t step, int64_t utime);
  void run_step(int64_t utime);
  void finish_step(int64_t utime);
  int64_t elapsed_ms(int64_t utime) const;
  int64_t step_limit_ms() const;
  int problem_index() const;  // 0..2 for problem steps, -1 otherwise
  void answer_stabilise(int64_t utime, const char* how);
  void answer_score(int64_t utime);
  bricklayer::study_problem_t problem_message(int index, int64_t utime) const;
  std::string instruction() const;

  SessionSetup setup_;
  std::array<std::shared_ptr<const StabiliseChecker>, 2> stabilise_;
  Problem score_problem_;
  SessionOutputs out_;

  int8_t step_ = bricklayer::study_session_t::STEP_WAITING;
  int8_t state_ = bricklayer::study_session_t::STATE_READY;
  std::array<int32_t, 7> attempts_{};  // per step
  int64_t elapsed_before_ms_ = 0;      // running time before the last pause
  int64_t running_since_ = 0;          // utime the step (re)started running
  std::optional<int64_t> clear_since_; // READY: since when the board has been empty

  // Trial:
  int32_t best_score_ = 0;
  int32_t best_blocks_ = 0;
  int32_t collapses_ = 0;
  std::optional<bool> last_balanced_;
  // Stabilise:
  std::optional<Observation> last_pile_;
  std::optional<Verdict> settled_verdict_;
  int64_t settled_since_ = 0;
  // Score:
  std::optional<ScoreJudge> judge_;
};

}  // namespace bricklayer::study
