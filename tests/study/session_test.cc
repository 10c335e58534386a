// The study protocol of one subject, driven directly with times and observations.
#include <map>
#include <memory>
#include <string>

#include <catch2/catch.hpp>

#include "bricklayer/core/predict.h"
#include "bricklayer/study/session.h"

using namespace bricklayer;
using namespace bricklayer::study;
using S = bricklayer::study_session_t;
using A = bricklayer::study_answer_t;

namespace {

std::string problem_path(const std::string& name) {
  return std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/" + name + ".json";
}

std::shared_ptr<const StabiliseChecker> checker(const std::string& name) {
  static std::map<std::string, std::shared_ptr<const StabiliseChecker>> cache;
  auto& c = cache[name];
  if (!c) c = std::make_shared<const StabiliseChecker>(load_problem(problem_path(name)));
  return c;
}

// Drives one protocol at 10 observations a second of a scripted board.
struct Driver {
  SessionProtocol protocol;
  int64_t now = 1'000'000'000'000;
  SessionOutputs seen;

  explicit Driver(SessionSetup setup = {"s1", "p1", Condition::kRed, 120'000, 1'000, 3'000})
      : protocol(setup, checker("stabilise-two"), checker("stabilise-one"), load_problem(problem_path("score-100-four"))) {}

  void collect() {
    SessionOutputs o = protocol.take_outputs();
    seen.trials.insert(seen.trials.end(), o.trials.begin(), o.trials.end());
    seen.answers.insert(seen.answers.end(), o.answers.begin(), o.answers.end());
    seen.problems.insert(seen.problems.end(), o.problems.begin(), o.problems.end());
    seen.rounds.insert(seen.rounds.end(), o.rounds.begin(), o.rounds.end());
  }
  // Shows `pile` (balanced/score from the exact annotator) for `ms`.
  void show(const core::Stack& pile, int64_t ms) {
    const bool balanced = pile.blocks.empty() || stands(pile, 0.005);
    const int32_t score = core::score_of(core::overhang(pile));
    for (int64_t t = 0; t < ms; t += 100) {
      now += 100'000;
      protocol.observe({now, true, pile, balanced, score});
      collect();
    }
  }
  void clear(int64_t ms = 1'200) { show(core::Stack{}, ms); }
};

core::Stack pile_of(std::vector<std::pair<int32_t, double>> blocks) {
  core::Stack s;
  int64_t id = 1;
  for (auto [row, x] : blocks) s.blocks.push_back({id++, row, x});
  return s;
}

const core::Stack kTrialPile = pile_of({{0, -0.75}, {1, -0.45}});          // stands, score 55
const core::Stack kFalling = pile_of({{0, -0.6}, {1, 0.3}});               // falls, score 130
const core::Stack kFourBlocks = pile_of({{0, -0.47855339}, {1, -1.15621109}, {1, 0.16789322}, {2, -0.53312874}});  // 117

}  // namespace

TEST_CASE("session: the whole protocol, step by step, with the display told what to say", "[session]") {
  Driver d;
  CHECK(d.protocol.state(d.now).step == S::STEP_WAITING);
  CHECK_FALSE(d.protocol.done(d.now));
  REQUIRE(d.protocol.start(d.now));
  CHECK_FALSE(d.protocol.start(d.now));
  CHECK(d.protocol.state(d.now).instruction == "Take every block off the board to begin the first game.");

  // Trial 1: a standing pile of 55, a falling one of 130 (does not count), one collapse.
  d.clear();
  CHECK(d.protocol.step_state() == S::STATE_RUNNING);
  CHECK(d.seen.rounds == std::vector<RoundCommand>{RoundCommand::kStart});
  CHECK(d.protocol.state(d.now).instruction.rfind("Build a pile", 0) == 0);
  d.show(kTrialPile, 60'000);
  d.show(kFalling, 5'000);
  d.show(kTrialPile, 60'000);
  REQUIRE(d.seen.trials.size() == 1);
  CHECK(d.seen.trials[0].trial == 1);
  CHECK(d.seen.trials[0].score == 55);
  CHECK(d.seen.trials[0].num_blocks == 2);
  CHECK(d.seen.trials[0].collapses == 1);
  CHECK(d.seen.trials[0].duration_ms == 120'000);
  CHECK(d.seen.trials[0].condition == S::CONDITION_RED);
  CHECK(d.protocol.step() == S::STEP_PROBLEM_1);
  CHECK(d.protocol.step_state() == S::STATE_READY);  // the trial's pile is still on the board

  // Problem 1: the subject builds the given pile with two counterweights; it settles by itself.
  d.clear();
  REQUIRE(d.seen.problems.size() == 1);
  CHECK(d.seen.problems[0].problem == 1);
  CHECK(d.seen.problems[0].minimum_added == 2);
  CHECK(d.seen.problems[0].num_blocks == 4);
  const Problem& p1 = checker("stabilise-two")->problem();
  d.show(p1.pile, 4'000);  // held by hand, falling: not an answer
  CHECK(d.seen.answers.empty());
  d.show(with_added(p1.pile, p1.solution), 3'100);
  REQUIRE(d.seen.answers.size() == 1);
  CHECK(d.seen.answers[0].problem == 1);
  CHECK(d.seen.answers[0].outcome == A::OUTCOME_CORRECT);
  CHECK(d.seen.answers[0].blocks_added == 2);
  CHECK(d.seen.answers[0].reason == "stands with 2 added blocks, the fewest possible (settled)");

  // Problem 2: the subject adds two blocks and says done: excess.
  d.clear();
  const Problem& p2 = checker("stabilise-one")->problem();
  d.show(with_added(p2.pile, {p2.solution[0], {0, -5.0}}), 1'000);
  REQUIRE(d.protocol.done(d.now));
  d.collect();
  REQUIRE(d.seen.answers.size() == 2);
  CHECK(d.seen.answers[1].outcome == A::OUTCOME_EXCESS);
  CHECK(d.seen.answers[1].blocks_added == 2);
  CHECK(d.seen.answers[1].minimum_added == 1);

  // Problem 3: the four-block optimum (117) held for a second after 10 s.
  d.clear();
  REQUIRE(d.seen.problems.size() == 3);
  CHECK(d.seen.problems[2].kind == bricklayer::study_problem_t::KIND_SCORE);
  d.show(kTrialPile, 10'000);
  d.show(kFourBlocks, 1'200);
  REQUIRE(d.seen.answers.size() == 3);
  CHECK(d.seen.answers[2].outcome == A::OUTCOME_CORRECT);
  CHECK(d.seen.answers[2].time_ms == 10'200);  // from the moment the step ran (the board clear for 1 s)

  // Trial 2 and the end.
  d.clear();
  d.show(kFourBlocks, 121'000);
  REQUIRE(d.seen.trials.size() == 2);
  CHECK(d.seen.trials[1].trial == 2);
  CHECK(d.seen.trials[1].score == 117);
  CHECK(d.protocol.finished());
  CHECK(d.protocol.state(d.now).step == S::STEP_DONE);
  CHECK(d.protocol.state(d.now).instruction == "That was all. Thank you!");
  CHECK(d.seen.rounds.size() == 4);  // start and reset of each game
}

TEST_CASE("session: pause stops the clock, repeat runs a step again with the next attempt, abort ends", "[session]") {
  Driver d;
  d.protocol.start(d.now);
  d.clear();
  d.show(kTrialPile, 50'000);
  REQUIRE(d.protocol.pause(d.now));
  CHECK(d.protocol.state(d.now).instruction == "Paused. Please wait.");
  const int64_t remaining = d.protocol.state(d.now).step_remaining_ms;
  d.show(kFourBlocks, 300'000);  // ignored while paused, and the clock stands still
  CHECK(d.protocol.state(d.now).step_remaining_ms == remaining);
  REQUIRE(d.protocol.resume(d.now));
  d.show(kTrialPile, 70'100);
  REQUIRE(d.seen.trials.size() == 1);
  CHECK(d.seen.trials[0].score == 55);

  // Repeat from READY of problem 1: the first game again, attempt 2.
  REQUIRE(d.protocol.repeat(d.now));
  CHECK(d.protocol.step() == S::STEP_TRIAL_1);
  CHECK(d.protocol.state(d.now).attempt == 2);
  d.clear();
  d.show(kFourBlocks, 120'100);
  REQUIRE(d.seen.trials.size() == 2);
  CHECK(d.seen.trials[1].attempt == 2);
  CHECK(d.seen.trials[1].score == 117);

  // Problem 1 runs out of time with the given pile still falling: failed.
  d.clear();
  d.show(checker("stabilise-two")->problem().pile, 180'100);
  REQUIRE(d.seen.answers.size() == 1);
  CHECK(d.seen.answers[0].outcome == A::OUTCOME_FAILED);
  CHECK(d.seen.answers[0].reason == "falls with 0 added blocks (time up)");

  REQUIRE(d.protocol.abort(d.now));
  d.collect();
  CHECK(d.protocol.finished());
  CHECK(d.protocol.state(d.now).state == S::STATE_ABORTED);
  CHECK_FALSE(d.protocol.resume(d.now));
  CHECK_FALSE(d.protocol.repeat(d.now));
  d.show(kFourBlocks, 5'000);
  CHECK(d.seen.answers.size() == 1);
}

TEST_CASE("session: bad setups are refused", "[session]") {
  const Problem score = load_problem(problem_path("score-100-four"));
  CHECK_THROWS_AS(SessionProtocol({"", "p", Condition::kBlue}, checker("stabilise-two"), checker("stabilise-one"), score),
                  std::invalid_argument);
  CHECK_THROWS_AS(SessionProtocol({"s", "p", Condition::kUnknown}, checker("stabilise-two"), checker("stabilise-one"), score),
                  std::invalid_argument);
  CHECK_THROWS_AS(SessionProtocol({"s", "p", Condition::kBlue}, checker("stabilise-two"), nullptr, score), std::invalid_argument);
  CHECK_THROWS_AS(SessionProtocol({"s", "p", Condition::kBlue}, checker("stabilise-two"), checker("stabilise-one"),
                                  checker("stabilise-one")->problem()),
                  std::invalid_argument);
}
