// The session driver as a node on the in-process rig: commands in, session messages and projection
// commands out, on the rig's clock.
#include <string>

#include <catch2/catch.hpp>

#include "bricklayer/command_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/messages/stack.h"
#include "bricklayer/study/channels.h"
#include "bricklayer/study/session_node.h"
#include "harness/rig.h"

using namespace bricklayer;
using namespace bricklayer::study;
using S = bricklayer::study_session_t;

namespace {

SessionConfig config_for(const std::string& subject, const std::string& condition) {
  SessionConfig c;
  c.subject = subject;
  c.condition = condition;
  c.session_id = "session-" + subject;
  const std::string dir = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/";
  c.problem_1 = dir + "stabilise-two.json";
  c.problem_2 = dir + "stabilise-one.json";
  c.problem_3 = dir + "score-100-four.json";
  c.trial_seconds = 10;  // short games: the protocol is the same
  return c;
}

// Publishes a stack and the exact annotator's prediction of it, as vision and prediction would.
struct Board {
  harness::Rig& rig;
  int64_t frame = 0;
  void show(const core::Stack& pile) {
    const bricklayer::stack_t s = messages::to_stack_message(pile, rig.now(), ++frame);
    rig.publish(channel(kStackChannel), s);
    core::PredictOptions options;
    options.position_tolerance = 0.005;
    const core::Prediction p = core::predict(pile, options);
    bricklayer::prediction_t m{};
    m.utime = s.utime;
    m.frame_number = s.frame_number;
    m.status = bricklayer::prediction_t::STATUS_OK;
    m.balanced = p.balanced;
    m.score = p.score;
    m.num_blocks = 0;
    rig.publish(channel(kPredictionChannel), m);
  }
  // `pile` at 10 frames a second for `seconds`.
  void hold(const core::Stack& pile, double seconds) {
    for (int k = 0; k < static_cast<int>(seconds * 10); ++k) {
      show(pile);
      rig.run_for(std::chrono::milliseconds(100));
    }
  }
};

void command(harness::Rig& rig, int8_t what, int64_t sequence) {
  bricklayer::study_command_t c{};
  c.utime = rig.now();
  c.command = what;
  c.sequence = sequence;
  rig.publish(channel(kStudyCommandChannel), c);
}

}  // namespace

TEST_CASE("session node: starts at once, tells projection the condition, runs and repeats steps on command", "[session_node]") {
  harness::Rig rig(10'000);
  auto& rec = rig.record({channel(kSessionChannel), channel(kTrialChannel), channel(kAnswerChannel),
                          channel(kProblemChannel), channel(kCommandChannel)});
  auto& node = rig.add<SessionNode>(config_for("p01", "blue"));
  Board board{rig};
  board.hold(core::Stack{}, 1.5);
  const auto running = rec.wait_for<S>(channel(kSessionChannel), [](const S& s) {
    return s.step == S::STEP_TRIAL_1 && s.state == S::STATE_RUNNING;
  });
  REQUIRE(running);
  CHECK(running->condition == S::CONDITION_BLUE);
  CHECK(running->session_id == "session-p01");
  const auto commands = rec.all<bricklayer::command_t>(channel(kCommandChannel));
  REQUIRE(commands.size() >= 2);
  CHECK(commands[0].command == bricklayer::command_t::SET_CONDITION);
  CHECK(commands[0].index == S::CONDITION_BLUE);
  CHECK(commands.back().command == bricklayer::command_t::START_ROUND);

  core::Stack pile;
  pile.blocks = {{1, 0, -0.75}, {2, 1, -0.45}};  // stands, score 55
  board.hold(pile, 5);
  command(rig, bricklayer::study_command_t::PAUSE, 1);
  command(rig, bricklayer::study_command_t::PAUSE, 1);  // the same message twice: once
  rig.run_for(std::chrono::seconds(30));
  CHECK(node.protocol().step_state() == S::STATE_PAUSED);
  CHECK(rec.all<bricklayer::study_trial_t>(channel(kTrialChannel)).empty());
  command(rig, bricklayer::study_command_t::RESUME, 2);
  board.hold(pile, 5.5);
  const auto trial = rec.wait_for<bricklayer::study_trial_t>(channel(kTrialChannel));
  REQUIRE(trial);
  CHECK(trial->score == 55);
  CHECK(trial->duration_ms == 10'000);
  CHECK(rec.all<bricklayer::command_t>(channel(kCommandChannel)).back().command == bricklayer::command_t::RESET_ROUND);

  // Problem 1 starts on a clear board and is published while it runs.
  board.hold(core::Stack{}, 1.5);
  const auto problem = rec.wait_for<bricklayer::study_problem_t>(channel(kProblemChannel));
  REQUIRE(problem);
  CHECK(problem->problem == 1);
  CHECK(problem->minimum_added == 2);
  command(rig, bricklayer::study_command_t::DONE, 3);  // nothing built yet: failed
  const auto answer = rec.wait_for<bricklayer::study_answer_t>(channel(kAnswerChannel));
  REQUIRE(answer);
  CHECK(answer->outcome == bricklayer::study_answer_t::OUTCOME_FAILED);

  command(rig, bricklayer::study_command_t::ABORT, 4);
  rig.run_for(std::chrono::milliseconds(100));
  const auto aborted = rec.wait_for<S>(channel(kSessionChannel), [](const S& s) { return s.state == S::STATE_ABORTED; });
  REQUIRE(aborted);
  CHECK(aborted->instruction == "The session has ended. Thank you!");
  CHECK(node.protocol().finished());
}

TEST_CASE("session node: --wait-for-start waits, bad problem files are refused", "[session_node]") {
  harness::Rig rig(10'000);
  auto& rec = rig.record({channel(kSessionChannel)});
  SessionConfig c = config_for("p02", "red");
  c.wait_for_start = true;
  auto& node = rig.add<SessionNode>(c);
  rig.run_for(std::chrono::seconds(3));
  CHECK(node.protocol().step() == S::STEP_WAITING);
  CHECK(rec.all<S>(channel(kSessionChannel)).size() >= 2);  // once a second while waiting
  command(rig, bricklayer::study_command_t::START, 9);
  rig.run_for(std::chrono::milliseconds(100));
  CHECK(node.protocol().step() == S::STEP_TRIAL_1);

  SessionConfig bad = config_for("p03", "proposed");
  bad.problem_1 = bad.problem_3;  // a score problem where a stabilise one belongs
  CHECK_THROWS_AS(rig.add<SessionNode>(bad), std::invalid_argument);
}
