// The simulated study end to end: scripted subjects (simcam scenarios written by `bricklayer-study script`)
// are played by the real simulated camera into the real vision, prediction and projection nodes and the
// study session driver, all on one in-process rig (its clock only: every run is the same); the bus is
// recorded the way the exhibit's logger records it (its moment detector and frame policy, into an LCM
// log), and the real `bricklayer-study report` of those logs must fill every Table 1 column as the scripts
// dictate. Projection's light is drawn into every camera frame (the closed loop), so the red of a falling
// pile under red and proposed reaches vision as it does at the exhibit.
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "bricklayer/common/channels.h"
#include "bricklayer/logger/moment_detector.h"
#include "bricklayer/logger/recording_policy.h"
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/runtime/log_file.h"
#include "bricklayer/simcam/simcam_node.h"
#include "bricklayer/round_t.hpp"
#include "bricklayer/study/channels.h"
#include "bricklayer/study/session_node.h"
#include "bricklayer/study/study_log.h"
#include "bricklayer/study/table.h"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_trial_t.hpp"
#include "bricklayer/vision/vision_node.h"
#include "harness/program.h"
#include "harness/rig.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::study;
using S = bricklayer::study_session_t;

namespace {

// What the test shortens, and why: six whole sessions as shipped (2-minute games, problem limits of 180, 180
// and 60 s, 30 frames a second) are about 61,000 frames, a quarter of an hour of CPU; this is 2,900, 50 s.
// - Games last kTrialSeconds (the driver's --trial-seconds, and the script's: `script --trial-seconds`).
// - The problems' time limits are kProblemSeconds, in copies of the shipped problem files with nothing
//   else changed (the piles, minima and solutions are the shipped ones): a failing subject holds its pile
//   until the limit.
// - simcam plays kFps frames a second. A script's board is empty for 1.5 s before each step, of which the
//   driver needs 1 s, and vision's default filter holds a lost block 3 frames and confirms a new one in 2
//   of 3: measured, the sessions run as scripted at 5 frames a second but not at 3 (problem 2 never
//   starts); 10 keeps a margin.
// Everything else is the exhibit's: vision, prediction and projection with their defaults, the driver's
// clear (1 s) and settle (3 s) times, the nuisance of the scripts (mild).
constexpr double kTrialSeconds = 10;
constexpr double kProblemSeconds = 15;
constexpr double kFps = 10;

struct Scripted {
  std::string subject;
  std::string kind;  // right, excess or failing
  Condition condition;
  int trial1, trial2;
  std::array<Outcome, 3> answers;
};

constexpr Outcome C = Outcome::kCorrect;
constexpr Outcome X = Outcome::kExcess;
constexpr Outcome F = Outcome::kFailed;

// The three shipped scripted subjects (launch/scenarios/study-subject-*.json), each under two
// conditions, so every condition has two subjects of different kinds and the ratio's variance is defined.
std::vector<Scripted> subjects() {
  const Scripted right{"", "right", Condition::kUnknown, 45, 70, {C, C, C}};
  const Scripted excess{"", "excess", Condition::kUnknown, 60, 66, {X, X, C}};
  const Scripted failing{"", "failing", Condition::kUnknown, 50, 40, {F, C, F}};
  auto as = [](Scripted s, const char* id, Condition c) {
    s.subject = id;
    s.condition = c;
    return s;
  };
  return {as(right, "e2e-b-right", Condition::kBlue),         as(excess, "e2e-b-excess", Condition::kBlue),
          as(excess, "e2e-r-excess", Condition::kRed),        as(failing, "e2e-r-failing", Condition::kRed),
          as(failing, "e2e-p-failing", Condition::kProposed), as(right, "e2e-p-right", Condition::kProposed)};
}

std::string answers_flag(const std::array<Outcome, 3>& a) {
  return to_string(a[0]) + "," + to_string(a[1]) + "," + to_string(a[2]);
}

// Copies of the shipped problems with only the time limit shortened.
void write_problems(const harness::ScratchDir& dir) {
  for (const char* name : {"stabilise-two", "stabilise-one", "score-100-four"}) {
    nlohmann::json p = nlohmann::json::parse(harness::read_file(harness::source_dir() / "launch/problems" / (std::string(name) + ".json")));
    p["time_limit_s"] = kProblemSeconds;
    harness::write_file(dir / "problems" / (std::string(name) + ".json"), p.dump(1));
  }
}

// The exhibit profiles' logger: every channel whole but camera frames, 2 frames a second outside
// 10-s full-rate windows around moments, answers thinned with their frames (logger README).
class ExhibitLogger {
 public:
  explicit ExhibitLogger(const std::string& path) : writer_(path), policy_(options()) {}

  void event(int64_t utime, const std::string& ch, const uint8_t* data, size_t size) {
    if (auto m = moments_.observe(ch, data, size, utime); m && logger::MomentDetector::wants_full_rate(*m))
      policy_.moment(utime);
    policy_.offer(logger::Event{utime, ch, std::vector<uint8_t>(data, data + size)});
    write(policy_.release(utime));
  }
  bool finish() {
    write(policy_.release_all());
    return ok_ && writer_.flush();
  }
  int64_t frames_kept() const { return policy_.frames_kept(); }
  int64_t frames_thinned() const { return policy_.frames_thinned(); }

 private:
  static logger::FramePolicyOptions options() {
    logger::FramePolicyOptions o;
    o.frame_channel = channel(kImageChannel);
    o.rate = 2;
    o.before_s = 10;
    o.after_s = 10;
    o.answer_channels = {channel(kStackChannel), channel(kPredictionChannel), channel(kTimingChannel),
                         channel(kPreviewChannel), channel(kTruthChannel)};
    return o;
  }
  void write(const std::vector<logger::Event>& events) {
    for (const logger::Event& e : events) ok_ = writer_.write(e.utime, e.channel, e.data.data(), e.data.size()) && ok_;
  }

  runtime::LogWriter writer_;
  logger::MomentDetector moments_;
  logger::RecordingPolicy policy_;
  bool ok_ = true;
};

struct Played {
  int64_t frames = 0;
  double simulated_s = 0;
  double wall_s = 0, cpu_s = 0;
  int64_t frames_logged = 0, frames_thinned = 0;
  std::optional<double> observations, unpaired;  // the driver's last heartbeat
};

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

// One scripted subject's whole session on a rig: simcam -> vision -> prediction -> session driver and
// projection, projection's light back into simcam's frames; the bus recorded into `log_path`.
Played play(const Scripted& who, const harness::ScratchDir& dir, const std::string& log_path) {
  const std::string scenario = (dir / (who.subject + ".json")).string();
  const harness::Ran made = harness::run_program(
      "bricklayer-study", {"script", "--trial1", std::to_string(who.trial1), "--trial2", std::to_string(who.trial2),
                           "--answers", answers_flag(who.answers), "--trial-seconds", std::to_string(kTrialSeconds),
                           "--problems", (dir / "problems").string(), scenario});
  INFO(made.err);
  REQUIRE(made.status.clean());

  harness::Rig rig(static_cast<int64_t>(1e6 / kFps));
  ExhibitLogger log(log_path);
  rig.hub().set_tap([&](const std::string&, const std::string& ch, const uint8_t* data, size_t size, int64_t utime) {
    log.event(utime, ch, data, size);
  });
  projection::ProjectionConfig pc;
  pc.headless = true;
  pc.mute = true;
  pc.condition = "proposed";  // the exhibit's default: the session must set its own
  auto& projector = rig.add<projection::ProjectionNode>(pc);
  rig.add<vision::VisionNode>(vision::VisionConfig{});
  rig.add<prediction::PredictionNode>(prediction::PredictionConfig{});
  simcam::SimcamConfig camera;
  camera.scenario = scenario;
  camera.fps = kFps;
  auto& simcam = rig.add<simcam::SimcamNode>(camera);
  SessionConfig sc;
  sc.subject = who.subject;
  sc.condition = to_string(who.condition);
  sc.session_id = "session-" + who.subject;
  sc.problem_1 = (dir / "problems/stabilise-two.json").string();
  sc.problem_2 = (dir / "problems/stabilise-one.json").string();
  sc.problem_3 = (dir / "problems/score-100-four.json").string();
  sc.trial_seconds = kTrialSeconds;
  auto& session = rig.add<SessionNode>(sc);
  auto& rec = rig.record({channel(kHeartbeatChannel)});

  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = cpu_seconds();
  const int64_t t0 = rig.now();
  // The scenario ends 3 s after its last step: a session still running then has lost its subject.
  const bool over = rig.run_until([&] { return session.protocol().finished(); }, std::chrono::seconds(600));
  INFO("step " << int(session.protocol().step()) << ", state " << int(session.protocol().step_state()) << " after "
               << simcam.frames_published() << " frames");
  REQUIRE(over);
  CHECK(session.protocol().step() == S::STEP_DONE);
  rig.run_for(std::chrono::milliseconds(2500));  // the driver lingers 2 s: the logger gets its last state
  REQUIRE(log.finish());
  CHECK(projector.condition() == static_cast<projection::DisplayCondition>(static_cast<int>(who.condition)));
  CHECK(projector.problems_rejected() == 0);

  Played p;
  p.frames = simcam.frames_published();
  p.simulated_s = static_cast<double>(rig.now() - t0) / 1e6;
  p.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  p.cpu_s = cpu_seconds() - cpu0;
  p.frames_logged = log.frames_kept();
  p.frames_thinned = log.frames_thinned();
  if (const auto hb = rec.last_heartbeat("study-session")) {
    p.observations = harness::heartbeat_value(*hb, "observations");
    p.unpaired = harness::heartbeat_value(*hb, "unpaired_predictions");
  }
  return p;
}

// What one log holds of the study and of projection's rounds.
struct LogContents {
  std::vector<bricklayer::study_trial_t> trials;
  std::vector<bricklayer::study_answer_t> answers;
  std::vector<bricklayer::round_t> rounds;
  size_t images = 0;
};

LogContents read_log(const std::string& path) {
  LogContents c;
  runtime::LogReader reader(path);
  runtime::LogEvent e;
  while (reader.next(e)) {
    if (e.channel == channel(kTrialChannel)) {
      if (auto m = runtime::decode<bricklayer::study_trial_t>(e.data)) c.trials.push_back(*m);
    } else if (e.channel == channel(kAnswerChannel)) {
      if (auto m = runtime::decode<bricklayer::study_answer_t>(e.data)) c.answers.push_back(*m);
    } else if (e.channel == channel(kRoundChannel)) {
      if (auto m = runtime::decode<bricklayer::round_t>(e.data)) c.rounds.push_back(*m);
    } else if (e.channel == channel(kImageChannel)) {
      ++c.images;
    }
  }
  return c;
}

// A CSV written by the report: its header's names, one map per row.
std::vector<std::map<std::string, std::string>> parse_csv(const std::string& text) {
  std::vector<std::map<std::string, std::string>> rows;
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> header;
  auto split = [](const std::string& l) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream ls(l);
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (!l.empty() && l.back() == ',') cells.push_back("");
    return cells;
  };
  while (std::getline(in, line)) {
    if (header.empty()) {
      header = split(line);
      continue;
    }
    const std::vector<std::string> cells = split(line);
    REQUIRE(cells.size() == header.size());
    std::map<std::string, std::string> row;
    for (size_t k = 0; k < cells.size(); ++k) row[header[k]] = cells[k];
    rows.push_back(row);
  }
  return rows;
}

// A score vision read as the script's: vision measures a block to about 0.002 block lengths (its README) and
// publishes changes of 0.01 or more, so a score (100 x the overhang) is within a point.
constexpr int kScorePoints = 1;

// The ratio trial 2 / trial 1 of scores each within kScorePoints of the script's: its least and greatest.
std::pair<double, double> ratio_bounds(int trial1, int trial2) {
  return {static_cast<double>(trial2 - kScorePoints) / (trial1 + kScorePoints),
          static_cast<double>(trial2 + kScorePoints) / (trial1 - kScorePoints)};
}

}  // namespace

TEST_CASE("the simulated study end to end: scripted subjects through simcam, vision, prediction, projection, the "
          "driver and the logger, and the report of their logs as the scripts dictate", "[study][end-to-end]") {
  harness::ScratchDir dir("study-end-to-end");
  write_problems(dir);
  const std::vector<Scripted> all = subjects();
  std::vector<std::string> logs;
  Played total;
  for (const Scripted& who : all) {
    INFO("subject " << who.subject << " (" << who.kind << ", " << to_string(who.condition) << ")");
    const std::string log = (dir / (who.subject + ".lcmlog")).string();
    const Played p = play(who, dir, log);
    logs.push_back(log);
    total.frames += p.frames;
    total.simulated_s += p.simulated_s;
    total.wall_s += p.wall_s;
    total.cpu_s += p.cpu_s;
    std::printf("%-14s %5lld frames (%lld logged, %lld thinned), %5.1f s simulated, %5.1f s wall, %5.1f s CPU\n",
                who.subject.c_str(), static_cast<long long>(p.frames), static_cast<long long>(p.frames_logged),
                static_cast<long long>(p.frames_thinned), p.simulated_s, p.wall_s, p.cpu_s);
    // Every frame vision measured reached the driver with its prediction.
    REQUIRE(p.observations);
    CHECK(*p.observations >= 0.9 * static_cast<double>(p.frames));
    CHECK(p.unpaired == 0.0);
    CHECK(p.frames_thinned > 0);  // the exhibit's frame policy was at work

    // What the log holds of this session: the games, the answers and projection's rounds.
    const LogContents c = read_log(log);
    CHECK(static_cast<int64_t>(c.images) == p.frames_logged);
    REQUIRE(c.trials.size() == 2);
    for (const auto& t : c.trials) {
      const int scripted = t.trial == 1 ? who.trial1 : who.trial2;
      INFO("trial " << int(t.trial) << ": scored " << t.score << ", scripted " << scripted);
      CHECK(std::abs(t.score - scripted) <= kScorePoints);
      CHECK(t.num_blocks == 4);
      CHECK(t.collapses == 0);
      CHECK(t.condition == static_cast<int8_t>(who.condition));
    }
    REQUIRE(c.answers.size() == 3);
    for (const auto& a : c.answers) {
      const size_t k = static_cast<size_t>(a.problem - 1);
      INFO("problem " << int(a.problem) << ": " << a.reason);
      CHECK(a.outcome == static_cast<int8_t>(who.answers[k]));
      CHECK(a.condition == static_cast<int8_t>(who.condition));
      if (k == 2) continue;
      // The added blocks vision saw: the file's solution, one more aside (excess), or only the one aside.
      const int minimum = k == 0 ? 2 : 1;
      CHECK(a.minimum_added == minimum);
      CHECK(a.blocks_added == (who.answers[k] == C ? minimum : who.answers[k] == X ? minimum + 1 : 1));
      CHECK(a.stands == (who.answers[k] != F));
    }
    // The condition is in every round projection played (the two games).
    int running = 0;
    for (const auto& r : c.rounds) {
      if (r.state != bricklayer::round_t::STATE_RUNNING) continue;
      ++running;
      CHECK(r.condition == static_cast<int8_t>(who.condition));
    }
    CHECK(running > 0);
  }
  std::printf("all: %lld frames, %.1f s simulated, %.1f s wall, %.1f s CPU\n", static_cast<long long>(total.frames),
              total.simulated_s, total.wall_s, total.cpu_s);

  // The table library on the logs: every session counts, as the scripts dictate.
  StudyCollector collector;
  for (const std::string& path : logs) CHECK(read_study_log(path, collector).bad_messages == 0);
  CHECK(collector.problems().empty());
  const std::vector<SessionRecord> sessions = collector.sessions();
  REQUIRE(sessions.size() == all.size());
  const StudyTable table = make_table(sessions);
  CHECK(table.excluded.empty());
  REQUIRE(table.rows.size() == 3);
  std::map<Condition, ConditionRow> rows;
  for (const ConditionRow& row : table.rows) rows[row.condition] = row;

  // The program on the same logs, both CSVs.
  const std::string rows_csv = (dir / "table1.csv").string(), tests_csv = (dir / "tests.csv").string();
  std::vector<std::string> args{"report", "--csv", rows_csv, "--tests-csv", tests_csv};
  args.insert(args.end(), logs.begin(), logs.end());
  const harness::Ran report = harness::run_program("bricklayer-study", args);
  INFO(report.out << report.err);
  REQUIRE(report.status.clean());
  std::printf("%s", report.out.c_str());
  const auto csv_rows = parse_csv(harness::read_file(rows_csv));
  REQUIRE(csv_rows.size() == 3);

  for (const Condition condition : {Condition::kBlue, Condition::kRed, Condition::kProposed}) {
    INFO("condition " << to_string(condition));
    REQUIRE(rows.count(condition) == 1);
    const ConditionRow& row = rows[condition];
    // From the scripts alone: subjects, solved and excess counts exactly; scores and the ratio's mean within what
    // vision measures.
    size_t n = 0;
    std::array<size_t, 3> solved{0, 0, 0}, excess{0, 0, 0};
    double t1 = 0, t2 = 0, ratio_low = 0, ratio_high = 0;
    for (const Scripted& s : all) {
      if (s.condition != condition) continue;
      ++n;
      t1 += s.trial1;
      t2 += s.trial2;
      const auto [low, high] = ratio_bounds(s.trial1, s.trial2);
      ratio_low += low;
      ratio_high += high;
      for (size_t k = 0; k < 3; ++k) {
        if (s.answers[k] != F) ++solved[k];
        if (s.answers[k] == X) ++excess[k];
      }
    }
    CHECK(row.subjects == n);
    CHECK(row.solved == solved);
    CHECK(row.excess == excess);
    CHECK(std::abs(row.trial1_mean - t1 / n) <= kScorePoints);
    CHECK(std::abs(row.trial2_mean - t2 / n) <= kScorePoints);
    CHECK(row.ratio.n == n);
    CHECK(row.ratio.mean >= ratio_low / n);
    CHECK(row.ratio.mean <= ratio_high / n);
    // The variance of the measured ratios: the subjects of a condition were scripted apart.
    CHECK(std::isfinite(row.ratio.variance));
    CHECK(row.ratio.variance > 0.0);

    // The report's row is the table's, every column filled.
    const std::map<std::string, std::string>* csv = nullptr;
    for (const auto& r : csv_rows)
      if (r.at("condition") == to_string(condition)) csv = &r;
    REQUIRE(csv);
    for (const auto& [name, value] : *csv) {
      INFO("column " << name);
      CHECK_FALSE(value.empty());
    }
    CHECK(std::stoul(csv->at("subjects")) == row.subjects);
    const char* problems[3][2] = {{"p1_solved", "p1_excess"}, {"p2_solved", "p2_excess"}, {"p3_solved", "p3_excess"}};
    for (size_t k = 0; k < 3; ++k) {
      CHECK(std::stoul(csv->at(problems[k][0])) == solved[k]);
      CHECK(std::stoul(csv->at(problems[k][1])) == excess[k]);
    }
    CHECK(std::stod(csv->at("trial1_mean")) == Approx(row.trial1_mean));
    CHECK(std::stod(csv->at("trial2_mean")) == Approx(row.trial2_mean));
    CHECK(std::stoul(csv->at("ratio_n")) == row.ratio.n);
    CHECK(std::stod(csv->at("ratio_mean")) == Approx(row.ratio.mean));
    CHECK(std::stod(csv->at("ratio_variance")) == Approx(row.ratio.variance));
  }

  // Every pair of conditions tested, every column filled.
  const auto pairs = parse_csv(harness::read_file(tests_csv));
  CHECK(pairs.size() == 3);
  for (const auto& pair : pairs) {
    for (const auto& [name, value] : pair) {
      INFO("pair " << pair.at("a") << "-" << pair.at("b") << ", column " << name);
      CHECK_FALSE(value.empty());
    }
    const double p = std::stod(pair.at("t_p"));
    CHECK(p > 0.0);
    CHECK(p <= 1.0);
  }
}
