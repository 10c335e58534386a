// The replay engine on logs written in-process (no network): matching by channel + utime +
// frame_number, mismatches, inputs dropped live, orphans, rejected inputs, adopting the recorded
// annotator.
#include "bricklayer/replay/replay.h"

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <filesystem>
#include <unistd.h>
#include <sstream>

#include "bricklayer/common/channels.h"
#include "bricklayer/prediction/prediction_logic.h"
#include "bricklayer/prediction/sample_stacks.h"
#include "bricklayer/replay/prediction_replay.h"
#include "bricklayer/timing_t.hpp"

using namespace bricklayer;

namespace {

template <typename T>
std::vector<uint8_t> bytes(const T& m) {
  std::vector<uint8_t> out(static_cast<size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : log_(std::make_unique<lcm::LogFile>(path, "w")) {
    REQUIRE(log_->good());
  }
  void write(const std::string& channel, const std::vector<uint8_t>& data) {
    lcm::LogEvent e{};
    e.eventnum = n_++;
    e.timestamp = 1'000'000 + n_ * 1000;
    e.channel = channel;
    e.datalen = static_cast<int32_t>(data.size());
    e.data = const_cast<uint8_t*>(data.data());
    REQUIRE(log_->writeEvent(&e) == 0);
  }

 private:
  std::unique_ptr<lcm::LogFile> log_;
  int64_t n_ = 0;
};

// One folder per test process, removed when the process ends.
struct TempFolder {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("bricklayer-replay-test-" + std::to_string(::getpid()));
  TempFolder() { std::filesystem::create_directories(path); }
  ~TempFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

std::string temp_log(const std::string& name) {
  static TempFolder folder;
  return (folder.path / name).string();
}

struct Recording {
  std::vector<stack_t> stacks;
  std::vector<prediction_t> predictions;
};

// A run of a live prediction process as its log would show it: every stack answered.
Recording record(const std::string& annotator, int n, double position_tolerance = prediction::kMeasuredPositionTolerance) {
  prediction::PredictionConfig config;
  config.annotator = annotator;
  config.position_tolerance = position_tolerance;
  prediction::PredictionLogic logic(config);
  Recording r;
  for (int i = 1; i <= n; ++i) {
    r.stacks.push_back(prediction::sample_stack(1 + i % 25, static_cast<uint32_t>(i), 100 + i, i));
    r.predictions.push_back(logic.answer(r.stacks.back()));
  }
  return r;
}

void write(const std::string& path, const Recording& r, int skip_prediction = -1, int skip_stack = -1) {
  LogWriter log(path);
  for (size_t i = 0; i < r.stacks.size(); ++i) {
    if (static_cast<int>(i) != skip_stack) log.write(channel(kStackChannel), bytes(r.stacks[i]));
    timing_t t{};
    t.frame_number = r.stacks[i].frame_number;
    t.elapsed_us = static_cast<int64_t>(1000 + i);  // differs run to run: never compared
    log.write(channel(kTimingChannel), bytes(t));
    if (static_cast<int>(i) != skip_prediction) log.write(channel(kPredictionChannel), bytes(r.predictions[i]));
  }
}

}  // namespace

TEST_CASE("a faithful log replays with 0 mismatches") {
  std::string path = temp_log("faithful.lcm");
  write(path, record("exact", 40));
  replay::PredictionReplay module("", "", 1000);
  std::ostringstream out;
  auto report = replay::replay_log(path, module, true, out);
  CHECK(report.inputs == 40);
  CHECK(report.compared == 40);
  CHECK(report.mismatches == 0);
  CHECK(report.not_in_log == 0);
  CHECK(report.orphans == 0);
  CHECK(report.ok());
  CHECK(report.summary().rfind("40 compared, 0 mismatches", 0) == 0);
  CHECK(out.str().empty());
}

TEST_CASE("an altered prediction is reported field by field") {
  Recording r = record("exact", 30);
  r.predictions[11].score += 1;
  r.predictions[20].blocks.at(0).state = r.predictions[20].blocks.at(0).state == 2 ? 0 : 2;
  std::string path = temp_log("altered.lcm");
  write(path, r);
  replay::PredictionReplay module("", "", 1000);
  std::ostringstream out;
  auto report = replay::replay_log(path, module, true, out);
  CHECK(report.compared == 30);
  CHECK(report.mismatches == 2);
  CHECK_FALSE(report.ok());
  CHECK(out.str().find("frame 12: score") != std::string::npos);
  CHECK(out.str().find("frame 21: block[0] state") != std::string::npos);
}

TEST_CASE("an input dropped live (newest wins) and an output without its input are not mismatches") {
  std::string path = temp_log("gaps.lcm");
  write(path, record("exact", 20), /*skip_prediction=*/5, /*skip_stack=*/9);
  replay::PredictionReplay module("", "", 1000);
  std::ostringstream out;
  auto report = replay::replay_log(path, module, true, out);
  CHECK(report.inputs == 19);
  CHECK(report.compared == 18);
  CHECK(report.not_in_log == 1);
  CHECK(report.orphans == 1);
  CHECK(report.mismatches == 0);
}

TEST_CASE("malformed and oversized inputs are rejected as the live process would") {
  std::string path = temp_log("bad-inputs.lcm");
  {
    LogWriter log(path);
    log.write(channel(kStackChannel), {1, 2, 3});
    log.write(channel(kStackChannel), bytes(prediction::sample_stack(30, 1, 1, 1)));  // > --max-blocks=10 bytes
    log.write(channel(kStackChannel), bytes(prediction::sample_stack(5, 2, 2, 2)));
  }
  replay::PredictionReplay module("", "", 10);
  std::ostringstream out;
  auto report = replay::replay_log(path, module, true, out);
  CHECK(report.inputs == 3);
  CHECK(report.rejected_inputs == 2);
  CHECK(report.outputs == 1);
}

TEST_CASE("the replay adopts the recorded annotator unless one is given") {
  std::string path = temp_log("paper.lcm");
  write(path, record("paper", 30));
  {
    replay::PredictionReplay module("", "", 1000);
    std::ostringstream out;
    auto report = replay::replay_log(path, module, true, out);
    CHECK(module.config().annotator == "paper");
    CHECK(report.mismatches == 0);
  }
  {
    replay::PredictionReplay module("exact", "", 1000);
    std::ostringstream out;
    auto report = replay::replay_log(path, module, true, out);
    CHECK(report.mismatches == 30);  // at least the annotator field differs in each
    CHECK(out.str().find("annotator paper (log) vs exact (replay)") != std::string::npos);
  }
}

TEST_CASE("the replay adopts the recorded position tolerance unless one is given") {
  std::string path = temp_log("tolerance.lcm");
  write(path, record("exact", 20, 0.02));
  {
    replay::PredictionReplay module("", "", 1000);
    std::ostringstream out;
    auto report = replay::replay_log(path, module, true, out);
    CHECK(module.config().position_tolerance == 0.02);
    CHECK(report.mismatches == 0);
  }
  {
    replay::PredictionReplay module("", "", 1000, 0.0);  // re-judged as exact positions: a choice
    std::ostringstream out;
    auto report = replay::replay_log(path, module, true, out);
    CHECK(report.mismatches == 20);  // at least the recorded tolerance differs in each
    CHECK(out.str().find("position_tolerance 0.02") != std::string::npos);
  }
  CHECK_THROWS_AS(replay::PredictionReplay("", "", 1000, -0.1), std::invalid_argument);
}

TEST_CASE("an unreadable log is an error") {
  replay::PredictionReplay module("", "", 1000);
  std::ostringstream out;
  CHECK_THROWS_AS(replay::replay_log("/nonexistent/run.lcm", module, true, out), std::runtime_error);
}
