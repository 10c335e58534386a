// Judging answers: stabilise problems (correct / excess / failed) and the timed score problem.
#include <string>

#include <catch2/catch.hpp>

#include "bricklayer/study/checker.h"
#include "bricklayer/study/problem.h"

using namespace bricklayer;
using namespace bricklayer::study;

namespace {

std::string problem_path(const std::string& name) {
  return std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/" + name + ".json";
}

const StabiliseChecker& two() {
  static const StabiliseChecker checker(load_problem(problem_path("stabilise-two")));
  return checker;
}

const StabiliseChecker& one() {
  static const StabiliseChecker checker(load_problem(problem_path("stabilise-one")));
  return checker;
}

// The given pile as vision would report it: other ids, positions off by a little, in centimetres.
core::Stack measured(const core::Stack& pile, double shift, const std::vector<Placement>& added = {}) {
  core::Stack s = with_added(pile, added);
  s.block_length = 7.5;
  s.table_edge = 12.0;
  s.block_height = 2.5;
  int64_t id = 100;
  for (auto& b : s.blocks) {
    b.id = id++;
    b.x = 12.0 + 7.5 * (b.x + shift);
  }
  return s;
}

}  // namespace

TEST_CASE("stabilise-two: two counterweights are correct, three blocks are excess, one fails", "[checker]") {
  const Problem& p = two().problem();
  CHECK(two().minimum().minimum == 2);

  const Verdict right = two().check(measured(p.pile, 0.003, p.solution), 41'000);
  CHECK(right.outcome == Outcome::kCorrect);
  CHECK(right.stands);
  CHECK(right.blocks_added == 2);
  CHECK(right.minimum_added == 2);
  CHECK(right.time_ms == 41'000);
  CHECK(right.reason == "stands with 2 added blocks, the fewest possible");

  // A third block on the surface far to the left changes nothing but counts.
  std::vector<Placement> three = p.solution;
  three.push_back({0, -5.0});
  const Verdict excess = two().check(measured(p.pile, 0.0, three));
  CHECK(excess.outcome == Outcome::kExcess);
  CHECK(excess.blocks_added == 3);
  CHECK(excess.reason == "stands with 3 added blocks; 2 suffice");

  // Only the left tower held: the right one still tips.
  const Verdict half = two().check(measured(p.pile, 0.0, {p.solution[0]}));
  CHECK(half.outcome == Outcome::kFailed);
  CHECK_FALSE(half.stands);
  CHECK(half.blocks_added == 1);
  CHECK(half.reason == "falls with 1 added block");

  // Nothing added.
  CHECK(two().check(measured(p.pile, 0.0)).outcome == Outcome::kFailed);
}

TEST_CASE("stabilise: moving or removing a given block fails, whatever stands", "[checker]") {
  const Problem& p = one().problem();
  // Pull the tipping top block back onto its support: the pile stands, but the problem was not solved.
  core::Stack moved = p.pile;
  moved.blocks[2].x -= 0.3;
  REQUIRE(stands(moved, p.position_tolerance));
  const Verdict v = one().check(moved);
  CHECK(v.outcome == Outcome::kFailed);
  CHECK(v.stands);
  CHECK(v.reason.find("the given block of row 1 at x = -0.6 was moved or removed") != std::string::npos);

  core::Stack removed = p.pile;
  removed.blocks.pop_back();
  CHECK(one().check(removed).outcome == Outcome::kFailed);

  // Within the match tolerance (0.05) it still counts as in place.
  CHECK(one().check(measured(p.pile, 0.04, {{2, -0.95}})).outcome == Outcome::kCorrect);
  CHECK(one().check(measured(p.pile, 0.06, {{2, -0.95}})).outcome == Outcome::kFailed);
}

TEST_CASE("stabilise: a pile that cannot be judged is a failed answer with the reason", "[checker]") {
  core::Stack bad = one().problem().pile;
  bad.blocks.push_back({99, 0, -2.0});  // overlaps the block at -2.4 in row 0
  const Verdict v = one().check(bad);
  CHECK(v.outcome == Outcome::kFailed);
  CHECK(v.reason.rfind("the pile could not be judged: ", 0) == 0);
}

TEST_CASE("problem files: what they declare is checked", "[checker][problems]") {
  const std::string pile = R"("pile": {"blocks": [{"row": 0, "x": -0.3}]})";
  auto file = [&](const std::string& rest) {
    return R"({"kind": "stabilise", "instruction": "Make it stand.", )" + pile + ", " + rest + "}";
  };
  // Declared minimum wrong (one block suffices).
  CHECK_THROWS_WITH(StabiliseChecker(parse_problem(file(R"("minimum_added": 2, "solution": [{"row": 1, "x": -0.7}, {"row": 2, "x": -0.7}])"))),
                    Catch::Contains("the file says 2 added blocks suffice at the fewest, the search says 1"));
  // Declared solution that falls.
  CHECK_THROWS_WITH(StabiliseChecker(parse_problem(file(R"("minimum_added": 1, "solution": [{"row": 1, "x": 0.5}])"))),
                    Catch::Contains("the declared solution does not stand"));
  CHECK_NOTHROW(StabiliseChecker(parse_problem(file(R"("minimum_added": 1, "solution": [{"row": 1, "x": -0.77}])"))));
  // Malformed files name the key.
  CHECK_THROWS_WITH(parse_problem(file(R"("minimum_added": 1, "solution": [{"row": 1, "x": -0.77}], "minimum": 1)")),
                    Catch::Contains("unknown key \"minimum\""));
  CHECK_THROWS_WITH(parse_problem(file(R"("minimum_added": 1, "solution": [])")),
                    Catch::Contains("\"solution\" has 0 blocks, \"minimum_added\" says 1"));
  CHECK_THROWS_WITH(parse_problem(R"({"kind": "score", "instruction": "x", "min_score": 100, "max_blocks": 4, "pile": {}})"),
                    Catch::Contains("\"pile\" does not belong in a \"score\" problem"));
  CHECK_THROWS_WITH(parse_problem(R"({"kind": "score", "instruction": "x", "min_score": 100, "max_blocks": 4})"),
                    Catch::Contains("positive \"time_limit_s\""));
  CHECK_THROWS_WITH(parse_problem("[1, 2"), Catch::Contains("not valid JSON"));
  CHECK_THROWS_WITH(parse_problem(R"({"kind": "stack"})"), Catch::Contains("\"kind\" must be \"stabilise\" or \"score\""));
  CHECK_THROWS_WITH(parse_problem(file(R"("minimum_added": 1, "solution": [{"row": 1, "x": "left"}])")),
                    Catch::Contains("solution[0].x\" must be a number"));
  CHECK_THROWS_WITH(parse_problem(R"({"kind": "stabilise", "instruction": "x", "minimum_added": 0, "pile": {"blocks": [{"row": 0, "x": -0.5}, {"row": 0, "x": -0.4}]}})"),
                    Catch::Contains("\"pile\": block 1 (id 1) overlaps"));
}

TEST_CASE("score problem: solved once a pile of at most four blocks has stood at 100 for a second, within the minute", "[checker]") {
  const Problem p = load_problem(problem_path("score-100-four"));
  CHECK(p.min_score == 100);
  CHECK(p.max_blocks == 4);
  CHECK(p.time_limit_ms == 60'000);
  CHECK(p.hold_ms == 1000);
  const int64_t t0 = 5'000'000;
  constexpr int64_t kFrame = 100'000;  // 10 predictions a second

  SECTION("held for a second: solved at the moment it was first reached") {
    ScoreJudge j(p);
    j.start(t0);
    int64_t t = t0;
    for (; t < t0 + 20'000'000; t += kFrame) j.observe(t, 4, true, 90);
    for (int k = 0; k <= 10; ++k, t += kFrame) j.observe(t, 4, true, 104);
    CHECK(j.solved());
    const Verdict v = j.verdict(t);
    CHECK(v.outcome == Outcome::kCorrect);
    CHECK(v.time_ms == 20'000);
    CHECK(v.score == 104);
    CHECK(v.reason == "reached 100 points with at most 4 blocks after 20.0 s");
  }
  SECTION("a pile that reaches 100 only while falling, or with five blocks, or for less than a second, does not count") {
    ScoreJudge j(p);
    j.start(t0);
    int64_t t = t0;
    for (int k = 0; k < 50; ++k, t += kFrame) j.observe(t, 4, false, 120);  // falling
    for (int k = 0; k < 50; ++k, t += kFrame) j.observe(t, 5, true, 130);   // five blocks
    for (int rep = 0; rep < 30; ++rep) {  // 0.9 s held, then a frame that falls: never a full second
      for (int k = 0; k < 9; ++k, t += kFrame) j.observe(t, 4, true, 101);
      j.observe(t, 4, false, 101);
      t += kFrame;
    }
    CHECK_FALSE(j.solved());
    CHECK(j.timed_out(t0 + 60'000'000));
    const Verdict v = j.verdict(t0 + 60'000'000);
    CHECK(v.outcome == Outcome::kFailed);
    CHECK(v.time_ms == 60'000);
    CHECK(v.score == 101);
  }
  SECTION("reached after the minute: failed") {
    ScoreJudge j(p);
    j.start(t0);
    for (int64_t t = t0 + 59'500'000; t < t0 + 62'000'000; t += kFrame) j.observe(t, 4, true, 110);
    CHECK_FALSE(j.solved());
    CHECK(j.verdict(t0 + 62'000'000).outcome == Outcome::kFailed);
  }
  SECTION("three blocks count too (at most four)") {
    ScoreJudge j(p);
    for (int64_t t = t0; t <= t0 + 1'000'000; t += kFrame) j.observe(t, 3, true, 100);
    CHECK(j.solved());
    CHECK(j.verdict(t0 + 1'000'000).time_ms == 0);
  }
  CHECK_THROWS_AS(ScoreJudge(load_problem(problem_path("stabilise-one"))), ProblemError);
}
