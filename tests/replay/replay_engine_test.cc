// bricklayer-replay (the real program) on runs recorded from the real nodes: every module replays with
// 0 mismatches, a tampered output of each is caught and named, a torn log fails the check whatever the
// mismatches, chains, --from/--to, the recorded configuration and --set, --diff between the paper and
// exact annotators (the seed paper's Figure 15 cases), --update.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>

#include "bricklayer/collapse_preview_t.hpp"
#include "bricklayer/common/channels.h"
#include "bricklayer/prediction_t.hpp"
#include "bricklayer/runtime/codec.h"
#include "bricklayer/runtime/log_file.h"
#include "harness/program.h"
#include "replay_cli.h"
#include "harness/scratch.h"
#include "replay_fixture.h"

using namespace bricklayer;
using namespace bricklayer::test;
namespace fs = std::filesystem;

namespace {


int64_t compared(const std::string& out) {
  std::smatch m;
  return std::regex_search(out, m, std::regex(R"((\d+) compared, 0 mismatches)")) ? std::stoll(m[1]) : -1;
}

// Rewrites the log with fn applied to every event (fn may change the data; returns false to drop it).
void rewrite(const std::string& path, const std::function<bool(runtime::LogEvent&)>& fn) {
  std::vector<runtime::LogEvent> events;
  {
    runtime::LogReader r(path);
    runtime::LogEvent e;
    while (r.next(e)) events.push_back(e);
  }
  runtime::LogWriter w(path);
  for (auto& e : events)
    if (fn(e)) w.write(e.utime, e.channel, e.data.data(), e.data.size());
}

}  // namespace

TEST_CASE("each module and the chain replay a recorded run with 0 mismatches") {
  harness::ScratchDir dir("replay-engine");
  const std::string log = (dir / "run.lcm").string();
  test::record_run(log, test::demo_stacks(300));
  for (const std::string module : {"prediction", "planner", "prediction,planner"}) {
    INFO(module);
    const auto r = replay({log, "--module", module, "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 0);
    CHECK(compared(r.out) > (module == "planner" ? 5 : 250));
    CHECK(r.err.find("with its recorded configuration") != std::string::npos);
    CHECK(r.err.find("never compared (run-to-run): timing_t, heartbeat_t, node_config_t") != std::string::npos);
  }
}

TEST_CASE("a tampered output of each module is caught, with its time, frame and field") {
  harness::ScratchDir dir("replay-tamper");
  const std::string log = (dir / "run.lcm").string();
  test::record_run(log, test::demo_stacks(300));
  SECTION("prediction") {
    int64_t frame = -1;
    rewrite(log, [&](runtime::LogEvent& e) {
      if (e.channel != channel(kPredictionChannel) || frame >= 0) return true;
      auto p = runtime::decode<prediction_t>(e.data);
      if (p->frame_number < 100 || p->num_blocks < 3) return true;
      p->blocks[2].state = p->blocks[2].state == 2 ? 0 : 2;
      frame = p->frame_number;
      e.data = runtime::encode(*p);
      return true;
    });
    const auto r = replay({log, "--module", "prediction,planner", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_PREDICTION (prediction_t) at ") != std::string::npos);
    CHECK(r.out.find("frame " + std::to_string(frame) + ": blocks[2].state: ") != std::string::npos);
    CHECK(r.out.find("first divergence: BL_PREDICTION") != std::string::npos);
    CHECK(r.out.find(" compared, 1 mismatches") != std::string::npos);
  }
  SECTION("planner") {
    bool done = false;
    rewrite(log, [&](runtime::LogEvent& e) {
      if (e.channel != channel(kPreviewChannel) || done) return true;
      auto p = runtime::decode<collapse_preview_t>(e.data);
      p->poses[1] += 1e-9;
      done = true;
      e.data = runtime::encode(*p);
      return true;
    });
    REQUIRE(done);
    const auto r = replay({log, "--module", "planner", "--check"});
    INFO(r.out << r.err);
    CHECK(r.status.code == 1);
    CHECK(r.out.find("MISMATCH BL_PREVIEW (collapse_preview_t)") != std::string::npos);
    CHECK(r.out.find("poses[1]: ") != std::string::npos);
  }
}

TEST_CASE("a torn log fails the check even with 0 mismatches, and the events after the tear are replayed") {
  harness::ScratchDir dir("replay-torn");
  const std::string log = (dir / "run.lcm").string();
  test::record_run(log, test::demo_stacks(300));
  const auto whole = replay({log, "--check"});
  REQUIRE(whole.status.code == 0);
  const int64_t all = compared(whole.out);
  // Tear one event in the middle: a write cut short, then the rest of the log (a full disk that came back).
  std::string bytes = harness::read_file(log);
  runtime::LogReader reader(log);
  runtime::LogEvent e;
  int64_t middle = 0;
  for (int i = 0; reader.next(e); ++i)
    if (e.channel == channel(kStackChannel) && e.offset > static_cast<int64_t>(bytes.size()) / 2) {
      middle = e.offset;
      break;
    }
  REQUIRE(middle > 0);
  bytes.erase(static_cast<size_t>(middle) + 40, 200);
  harness::write_file(log, bytes);
  const auto r = replay({log, "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 3);
  CHECK(r.out.find("DAMAGED " + log + ": ") != std::string::npos);
  CHECK(r.out.find("intact events after it were read and replayed") != std::string::npos);
  CHECK(r.out.find("THE LOG IS DAMAGED OR INCOMPLETE") != std::string::npos);
  // The events after the tear were compared too: all but what the tear took.
  std::smatch m;
  REQUIRE(std::regex_search(r.out, m, std::regex(R"((\d+) compared, 0 mismatches)")));
  CHECK(std::stoll(m[1]) >= all - 2);
  // A truncated end is damage too.
  bytes.resize(bytes.size() - 10);
  harness::write_file(log, bytes);
  CHECK(replay({log, "--check"}).status.code == 3);
}

TEST_CASE("the recorded configuration is adopted, --set overrides it, --from/--to narrow the range") {
  harness::ScratchDir dir("replay-config");
  const std::string log = (dir / "run.lcm").string();
  test::RunOptions o;
  o.prediction.annotator = "paper";
  o.planner = false;
  test::record_run(log, test::demo_stacks(300), o);
  auto r = replay({log, "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  CHECK(r.err.find("\"annotator\":\"paper\"") != std::string::npos);
  r = replay({log, "--check", "--set", "annotator=exact"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);
  CHECK(r.out.find("annotator: paper (log) vs exact (replay)") != std::string::npos);
  r = replay({log, "--check", "--set", "annotator=magic"});
  CHECK(r.status.code == 1);
  CHECK(r.err.find("annotator must be one of") != std::string::npos);
  r = replay({log, "--check", "--from", "2", "--to", "+4s"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  const int64_t n = compared(r.out);
  CHECK(n >= 55);  // 2 s of stacks at 30 a second
  CHECK(n <= 62);
}

TEST_CASE("diff: the paper annotator against exact lists the Figure 15 disagreements") {
  harness::ScratchDir dir("replay-diff");
  const std::string log = (dir / "fig15.lcm").string();
  test::RunOptions o;
  o.planner = false;
  test::record_run(log, test::figure15_stacks(), o);
  const auto r = replay({log, "--diff", "--set-b", "annotator=paper"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);  // they differ
  CHECK(r.out.find("| BL_PREDICTION | 30 |") != std::string::npos);
  CHECK(r.out.find("verdicts: ") != std::string::npos);
  // Case (c): the upper block rides on the falling middle block; the paper's LP marks only causes.
  CHECK(r.out.find("block 2 moving -> stable") != std::string::npos);
  CHECK(r.out.find("frame 20 (3 blocks)") != std::string::npos);
  CHECK(r.out.find("annotator 30") != std::string::npos);
}

TEST_CASE("update: --update rewrites a regression log's expected outputs, which then check") {
  harness::ScratchDir dir("replay-update");
  const std::string log = (dir / "regression.lcm").string();
  test::record_run(log, test::demo_stacks(120));
  rewrite(log, [](runtime::LogEvent& e) { return e.channel != channel(kPredictionChannel) || e.utime % 7 != 0; });
  rewrite(log, [](runtime::LogEvent& e) {
    if (e.channel != channel(kPredictionChannel)) return true;
    auto p = runtime::decode<prediction_t>(e.data);
    p->score += 1;  // a change meant: the expectations must follow
    e.data = runtime::encode(*p);
    return true;
  });
  CHECK(replay({log, "--module", "prediction,planner", "--check"}).status.code == 1);
  const auto u = replay({log, "--module", "prediction,planner", "--update"});
  INFO(u.out << u.err);
  REQUIRE(u.status.code == 0);
  CHECK(u.out.find("expected outputs of prediction,planner rewritten") != std::string::npos);
  const auto r = replay({log, "--module", "prediction,planner", "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  CHECK(compared(r.out) >= 120);
}
