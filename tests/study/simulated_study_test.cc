// The simulated study: twelve scripted subjects (simcam scenarios written from their scripts: games to a
// given score, answers right, with excess blocks or failing) play whole sessions under the three
// conditions through the real prediction logic and the real session driver, on the in-process rig's
// clock; the bus is recorded into one LCM log per condition, and the report of those logs must have
// every column the scripts dictate.
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <map>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/messages/stack.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/simcam/scenario.h"
#include "bricklayer/study/channels.h"
#include "bricklayer/study/session_node.h"
#include "bricklayer/study/study_log.h"
#include "bricklayer/study/subject_script.h"
#include "bricklayer/study/table.h"
#include "harness/rig.h"

using namespace bricklayer;
using namespace bricklayer::study;
using S = bricklayer::study_session_t;

namespace {

constexpr Outcome C = Outcome::kCorrect;
constexpr Outcome X = Outcome::kExcess;
constexpr Outcome F = Outcome::kFailed;

struct Scripted {
  std::string subject;
  Condition condition;
  SubjectScript script;
};

std::vector<Scripted> subjects() {
  return {
      {"b1", Condition::kBlue, {50, 55, {C, C, C}, ""}},     {"b2", Condition::kBlue, {60, 60, {X, C, F}, ""}},
      {"b3", Condition::kBlue, {40, 48, {F, X, C}, ""}},     {"b4", Condition::kBlue, {70, 63, {C, F, F}, ""}},
      {"r1", Condition::kRed, {50, 65, {C, X, C}, ""}},      {"r2", Condition::kRed, {45, 54, {X, X, F}, ""}},
      {"r3", Condition::kRed, {80, 88, {C, C, C}, ""}},      {"r4", Condition::kRed, {60, 90, {F, C, C}, ""}},
      {"p1", Condition::kProposed, {50, 80, {C, C, C}, ""}}, {"p2", Condition::kProposed, {40, 72, {C, C, F}, ""}},
      {"p3", Condition::kProposed, {60, 90, {X, C, C}, ""}}, {"p4", Condition::kProposed, {55, 110, {C, F, C}, ""}},
  };
}

std::string problem_path(const std::string& name) {
  return std::string(BRICKLAYER_SOURCE_DIR) + "/launch/problems/" + name + ".json";
}

// Plays one scripted subject's scenario at 10 frames a second into a session driver, recording the bus.
void run_session(const Scripted& who, runtime::LogWriter& log) {
  SessionConfig config;
  config.subject = who.subject;
  config.condition = to_string(who.condition);
  config.session_id = "sim-" + who.subject;
  config.problem_1 = problem_path("stabilise-two");
  config.problem_2 = problem_path("stabilise-one");
  config.problem_3 = problem_path("score-100-four");
  SessionSetup timing;
  timing.trial_ms = static_cast<int64_t>(config.trial_seconds * 1000);
  timing.clear_ms = static_cast<int64_t>(config.clear_seconds * 1000);
  timing.settle_ms = static_cast<int64_t>(config.settle_seconds * 1000);
  const simcam::Scenario scenario = simcam::parse_scenario(
      subject_scenario_json(who.script, timing, load_problem(config.problem_1), load_problem(config.problem_2),
                            load_problem(config.problem_3)),
      who.subject);

  harness::Rig rig(100'000);
  rig.hub().set_tap([&](const std::string&, const std::string& channel, const uint8_t* data, size_t size, int64_t utime) {
    log.write(utime, channel, data, size);
  });
  auto& node = rig.add<SessionNode>(config);
  const prediction::PredictionLogic logic(prediction::PredictionConfig{});
  const int64_t t0 = rig.now();
  int64_t frame = 0;
  while (!node.protocol().finished()) {
    const double t = static_cast<double>(rig.now() - t0) / 1e6;
    if (t >= scenario.duration_s) FAIL("the script ran out before the session ended, at step " << int(node.protocol().step()));
    const stack_t s = messages::to_stack_message(scenario.stack_at(t), rig.now(), ++frame);
    rig.publish(channel(kStackChannel), s);
    rig.publish(channel(kPredictionChannel), logic.answer(s));
    rig.step();
  }
  rig.run_for(std::chrono::seconds(1));  // the final state, as the logger would get it
  CHECK(node.protocol().step() == S::STEP_DONE);
}

}  // namespace

TEST_CASE("simulated study: twelve scripted subjects, three conditions, the report as the scripts dictate", "[simulated]") {
  const std::vector<Scripted> all = subjects();
  std::vector<std::string> logs;
  for (Condition c : {Condition::kBlue, Condition::kRed, Condition::kProposed}) {
    const std::string path = std::string(BRICKLAYER_BINARY_DIR) + "/tests/study/simulated_" + to_string(c) + "_" +
                             std::to_string(getpid()) + ".lcmlog";
    runtime::LogWriter log(path);
    for (const Scripted& s : all) {
      if (s.condition != c) continue;
      INFO("subject " << s.subject);
      run_session(s, log);
    }
    REQUIRE(log.flush());
    logs.push_back(path);
  }

  StudyCollector collector;
  for (const std::string& path : logs) {
    const LogReadCounts counts = read_study_log(path, collector);
    CHECK(counts.bad_messages == 0);
  }
  CHECK(collector.problems().empty());
  const StudyTable table = make_table(collector.sessions());
  CHECK(table.excluded.empty());
  REQUIRE(table.rows.size() == 3);

  // What the scripts dictate, computed from the scripts alone.
  for (const ConditionRow& row : table.rows) {
    INFO("condition " << to_string(row.condition));
    std::vector<double> t1, t2, ratio;
    std::array<size_t, 3> solved{0, 0, 0}, excess{0, 0, 0};
    for (const Scripted& s : all) {
      if (s.condition != row.condition) continue;
      t1.push_back(s.script.trial1_score);
      t2.push_back(s.script.trial2_score);
      ratio.push_back(static_cast<double>(s.script.trial2_score) / s.script.trial1_score);
      for (size_t k = 0; k < 3; ++k) {
        if (s.script.answers[k] != Outcome::kFailed) ++solved[k];
        if (s.script.answers[k] == Outcome::kExcess) ++excess[k];
      }
    }
    CHECK(row.subjects == 4);
    CHECK(row.trial1_mean == Approx(summarise(t1).mean));
    CHECK(row.trial2_mean == Approx(summarise(t2).mean));
    CHECK(row.solved == solved);
    CHECK(row.excess == excess);
    CHECK(row.ratio.mean == Approx(summarise(ratio).mean));
    CHECK(row.ratio.variance == Approx(summarise(ratio).variance));
  }
  REQUIRE(table.pairs.size() == 3);
  for (const PairRow& p : table.pairs) {
    CHECK(p.f.valid);
    CHECK(p.t.valid);
    CHECK(p.t.p > 0.0);
    CHECK(p.t.p <= 1.0);
  }
  // The scripts make the proposed condition improve most: its ratio differs from blue's.
  CHECK(table.pairs[1].a == Condition::kBlue);
  CHECK(table.pairs[1].b == Condition::kProposed);
  CHECK(table.pairs[1].t.p < 0.05);

  // The program on the same logs: the same table, every column filled.
  std::string command = std::string(BRICKLAYER_BINARY_DIR) + "/bin/bricklayer-study report --csv - ";
  for (const std::string& path : logs) command += path + " ";
  const std::string out_path = logs[0] + ".csv";
  REQUIRE(std::system((command + "> " + out_path + " 2>/dev/null").c_str()) == 0);
  std::FILE* f = std::fopen(out_path.c_str(), "r");
  REQUIRE(f);
  char line[512];
  int rows = 0;
  while (std::fgets(line, sizeof line, f)) {
    const std::string l(line);
    if (l.rfind("condition,", 0) == 0) continue;
    ++rows;
    CHECK(l.find(",,") == std::string::npos);  // no empty column
  }
  std::fclose(f);
  CHECK(rows == 3);
  for (const std::string& path : logs) std::remove(path.c_str());
  std::remove(out_path.c_str());
}

TEST_CASE("scripted piles score what they are asked to and stand", "[simulated]") {
  for (int32_t score : {1, 40, 55, 90, 104, 105, 110, 117}) {
    INFO("score " << score);
    const core::Stack pile = pile_with_score(score);
    CHECK(stands(pile, 0.005));
    CHECK(core::score_of(core::overhang(pile)) == score);
  }
  CHECK_THROWS_AS(pile_with_score(118), std::invalid_argument);
  CHECK_THROWS_AS(pile_with_score(0), std::invalid_argument);
}

TEST_CASE("the shipped scripted subjects are what bricklayer-study script writes", "[simulated]") {
  const std::string dir = std::string(BRICKLAYER_SOURCE_DIR) + "/launch/";
  const Problem p1 = load_problem(dir + "problems/stabilise-two.json");
  const Problem p2 = load_problem(dir + "problems/stabilise-one.json");
  const Problem p3 = load_problem(dir + "problems/score-100-four.json");
  struct Shipped {
    const char* file;
    SubjectScript script;
  };
  for (const Shipped& s : {Shipped{"study-subject-right", {45, 70, {C, C, C}, ""}},
                           Shipped{"study-subject-excess", {60, 66, {X, X, C}, ""}},
                           Shipped{"study-subject-failing", {50, 40, {F, C, F}, ""}}}) {
    INFO(s.file);
    std::ifstream in(dir + "scenarios/" + s.file + ".json");
    std::stringstream text;
    text << in.rdbuf();
    CHECK(text.str() == subject_scenario_json(s.script, SessionSetup{}, p1, p2, p3) + "\n");
    CHECK_NOTHROW(simcam::load_scenario(dir + "scenarios/" + s.file + ".json"));
  }
}
