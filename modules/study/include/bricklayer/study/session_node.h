// bricklayer-study-session: runs one subject's study session on the bus (the protocol of session.h).
//
// Subscribes: BL_STACK (stack_t, vision) and BL_PREDICTION (prediction_t, prediction): each prediction
//             with the stack it answers (same frame number) is one observation of the board;
//             BL_STUDY_COMMAND (study_command_t): start, pause, resume, repeat, abort, done.
// Publishes:  BL_STUDY_SESSION (study_session_t) on every change and once a second, with what the
//             display tells the subject; BL_STUDY_PROBLEM (study_problem_t) when a problem step runs and
//             once a second while it does; BL_STUDY_TRIAL and BL_STUDY_ANSWER (study_trial_t,
//             study_answer_t) once per result; BL_COMMAND (command_t): SET_CONDITION before each game,
//             START_ROUND when a game runs, RESET_ROUND when it ends.
// Time is the bus clock only, so a recorded session replays to the same outputs. The node stops by
// itself two seconds after the session is over (done or aborted), so the logger has the last state.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/config.h"
#include "bricklayer/runtime/node.h"
#include "bricklayer/stack_t.hpp"
#include "bricklayer/study/session.h"
#include "bricklayer/study_command_t.hpp"

namespace bricklayer::study {

struct SessionConfig {
  std::string subject;
  std::string condition = "proposed";
  std::string session_id;  // "" = subject and start time
  std::string problem_1 = "launch/problems/stabilise-two.json";
  std::string problem_2 = "launch/problems/stabilise-one.json";
  std::string problem_3 = "launch/problems/score-100-four.json";
  double trial_seconds = 120.0;
  double clear_seconds = 1.0;
  double settle_seconds = 3.0;
  bool wait_for_start = false;

  template <typename Visitor>
  void visit(Visitor& v) {
    v(runtime::param("subject", subject, "the experimenter's code for the subject (never a name)")
          .must([](const std::string& s) { return s.empty() ? std::string("a subject code is needed") : std::string(); }));
    v(runtime::param("condition", condition, "what the projector shows: blue (always blue), red (all red while it falls), proposed (causes red)")
          .one_of({"blue", "red", "proposed"}));
    v(runtime::param("session-id", session_id, "unique id of this session (default: subject and start time)"));
    v(runtime::param("problem-1", problem_1, "problem 1 (stabilise) file").existing_file());
    v(runtime::param("problem-2", problem_2, "problem 2 (stabilise) file").existing_file());
    v(runtime::param("problem-3", problem_3, "problem 3 (score) file").existing_file());
    v(runtime::param("trial-seconds", trial_seconds, "length of each game, seconds").range(1, 3600));
    v(runtime::param("clear-seconds", clear_seconds, "the board must be empty this long before a step runs, seconds").range(0, 60));
    v(runtime::param("settle-seconds", settle_seconds, "a complete standing answer unchanged this long is taken, seconds").range(0.5, 60));
    v(runtime::param("wait-for-start", wait_for_start, "wait for a START study command instead of starting at once"));
  }
};

class SessionNode final : public runtime::Node {
 public:
  using Config = SessionConfig;
  static constexpr const char* kProgram = "bricklayer-study-session";
  static constexpr const char* kSummary =
      "Runs one subject's study session: trial 1 (a game), problems 1-3, trial 2, with the display telling the "
      "subject what to do; the experimenter can pause, repeat a step or abort (bricklayer-study send ...).";

  SessionNode(const SessionConfig& config, runtime::Bus& bus);

  const SessionProtocol& protocol() const { return *protocol_; }

 protected:
  void tick() override;
  void before_heartbeat() override;

 private:
  void handle_stack(const bricklayer::stack_t& msg);
  void handle_prediction(const bricklayer::prediction_t& msg);
  void handle_command(const bricklayer::study_command_t& msg);
  void flush();
  void publish_state();
  void send_command(int32_t command, int32_t index);

  SessionConfig config_;
  std::unique_ptr<SessionProtocol> protocol_;
  std::deque<bricklayer::stack_t> stacks_;  // the newest few, to pair with their predictions
  int64_t last_state_utime_ = -1;
  int64_t last_problem_utime_ = -1;
  std::optional<int64_t> finished_utime_;
  int64_t command_sequence_ = 0;
  std::optional<int64_t> last_study_sequence_;
  int64_t observations_ = 0;
  int64_t unpaired_ = 0;
  std::string session_channel_, problem_channel_, trial_channel_, answer_channel_, command_channel_;
};

}  // namespace bricklayer::study
