// bricklayer-overhang-table as a program: a run stopped after some n and continued from its checkpoint
// writes byte for byte the files of a run that was never stopped; a checkpoint is continued only under the
// options that made it.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/program.h"
#include "harness/scratch.h"

using namespace bricklayer;

namespace {

// The table program in dir, writing its three files there; extra flags after.
harness::Ran table_run(const harness::ScratchDir& dir, std::vector<std::string> extra) {
  std::vector<std::string> args{"--table", (dir / "table.json").string(), "--stacks", (dir / "stacks.json").string(),
                                "--checkpoint", (dir / "checkpoint.json").string(), "--jobs", "2"};
  args.insert(args.end(), extra.begin(), extra.end());
  return harness::run_program("bricklayer-overhang-table", args, std::chrono::seconds(240));
}

}  // namespace

TEST_CASE("a run continued from its checkpoint writes the files of a run that was never stopped") {
  // n = 10: past 8, where the seeded brick-wall starts join (the random engine's state must carry over).
  harness::ScratchDir whole("overhang-whole"), parts("overhang-parts");
  const harness::Ran straight = table_run(whole, {"--max-n", "10"});
  REQUIRE(straight.status.code == 0);
  const harness::Ran first = table_run(parts, {"--max-n", "8"});
  REQUIRE(first.status.code == 0);
  const nlohmann::json checkpoint = nlohmann::json::parse(harness::read_file(parts / "checkpoint.json"));
  CHECK(checkpoint.at("stacks").size() == 8);
  CHECK(checkpoint.at("beam").size() >= 2);
  const harness::Ran rest = table_run(parts, {"--max-n", "10", "--continue"});
  INFO(rest.err);
  REQUIRE(rest.status.code == 0);
  CHECK(rest.err.find("continuing from") != std::string::npos);
  CHECK(rest.err.find("n=10 overhang") != std::string::npos);
  CHECK(harness::read_file(parts / "table.json") == harness::read_file(whole / "table.json"));
  CHECK(harness::read_file(parts / "stacks.json") == harness::read_file(whole / "stacks.json"));
  CHECK(harness::read_file(parts / "checkpoint.json") == harness::read_file(whole / "checkpoint.json"));
  const nlohmann::json table = nlohmann::json::parse(harness::read_file(parts / "table.json"));
  CHECK(table.size() == 10);
  CHECK(table.at("4").get<double>() == Approx(1.167893).margin(1e-6));
}

TEST_CASE("a checkpoint is continued only under the options that made it, and a broken one is refused") {
  harness::ScratchDir dir("overhang-refused");
  REQUIRE(table_run(dir, {"--max-n", "5"}).status.code == 0);
  const std::string table = harness::read_file(dir / "table.json");

  const harness::Ran other_seed = table_run(dir, {"--max-n", "7", "--continue", "--seed", "2"});
  CHECK(other_seed.status.code == 2);
  CHECK(other_seed.err.find("was written with other options") != std::string::npos);

  const harness::Ran not_further = table_run(dir, {"--max-n", "5", "--continue"});
  CHECK(not_further.status.code == 2);
  CHECK(not_further.err.find("already reaches n = 5") != std::string::npos);

  nlohmann::json broken = nlohmann::json::parse(harness::read_file(dir / "checkpoint.json"));
  broken["rng"] = "not an engine state";
  harness::write_file(dir / "checkpoint.json", broken.dump());
  const harness::Ran unreadable = table_run(dir, {"--max-n", "7", "--continue"});
  CHECK(unreadable.status.code != 0);
  CHECK(unreadable.err.find("unreadable random engine state") != std::string::npos);

  harness::write_file(dir / "checkpoint.json", "{\"options\": ");
  const harness::Ran not_json = table_run(dir, {"--max-n", "7", "--continue"});
  CHECK(not_json.status.code == 2);
  CHECK(not_json.err.find("is not JSON") != std::string::npos);
  CHECK(harness::read_file(dir / "table.json") == table);  // a refused continuation leaves the files alone
}
