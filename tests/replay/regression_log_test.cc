// The regression log kept with the tests (tests/data/replay/regression.lcm, made by
// bricklayer-replay-record-regression): replayed in CI, so a change in a module's behaviour fails here;
// --update rewrites its expected outputs when a change is meant (a scratch copy: the changed setting
// fails the check, --update with it rewrites the outputs and the configuration, the next check
// passes without it).
#include <catch2/catch.hpp>

#include <filesystem>
#include <regex>

#include "harness/program.h"
#include "replay_cli.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::test;
namespace fs = std::filesystem;

namespace {
const std::string kLog = std::string(BRICKLAYER_SOURCE_DIR) + "/tests/data/replay/regression.lcm";
const std::string kModules = "vision,prediction,planner,projection";


}  // namespace

TEST_CASE("the regression log replays with 0 mismatches in every module") {
  REQUIRE(fs::file_size(kLog) < 1'000'000);
  const auto r = replay({kLog, "--module", kModules, "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  CHECK(compared_on(r.out, "BL_STACK") >= 35);
  CHECK(compared_on(r.out, "BL_PREDICTION") >= 35);
  CHECK(compared_on(r.out, "BL_ROUND") >= 4);
  CHECK(compared_on(r.out, "BL_PROJECTOR") >= 10);
  CHECK(r.out.find(" 0 not in the log, 0 recorded outputs without their input") != std::string::npos);
}

TEST_CASE("update: a changed setting fails the check, --update with it rewrites the expected outputs, and the next check passes") {
  harness::ScratchDir dir("replay-regression-update");
  const std::string copy = (dir / "regression.lcm").string();
  fs::copy_file(kLog, copy);
  const std::string changed = "prediction.annotator=paper";
  auto r = replay({copy, "--module", kModules, "--check", "--set", changed});
  INFO(r.out << r.err);
  CHECK(r.status.code == 1);
  CHECK(r.out.find("annotator: exact (log) vs paper (replay)") != std::string::npos);
  r = replay({copy, "--module", kModules, "--update", "--set", changed});
  INFO(r.out << r.err);
  REQUIRE(r.status.code == 0);
  CHECK(r.out.find("expected outputs of " + kModules + " rewritten") != std::string::npos);
  r = replay({copy, "--module", kModules, "--check"});
  INFO(r.out << r.err);
  CHECK(r.status.code == 0);
  CHECK(r.err.find("\"annotator\":\"paper\"") != std::string::npos);  // the recorded configuration followed
  CHECK(compared_on(r.out, "BL_PREDICTION") >= 35);
  // The kept log itself is untouched.
  CHECK(replay({kLog, "--module", kModules, "--check"}).status.code == 0);
}
