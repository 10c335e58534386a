#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "bricklayer/runtime/config.h"
#include "harness/scratch.h"

using namespace bricklayer;
using namespace bricklayer::runtime;

namespace {
struct ExampleConfig {
  std::string annotator = "exact";
  double tolerance = 0.005;
  int64_t max_blocks = 1000;
  int hold = 3;
  bool no_filter = false;
  std::string scenario;
  std::string confirm = "2/3";
  double rate = 30;
  template <typename Visitor>
  void visit(Visitor& v) {
    v(param("annotator", annotator, "which blocks are red").one_of({"exact", "paper", "balance"}));
    v(param("tolerance", tolerance, "block lengths").range(0, 0.05));
    v(param("max-blocks", max_blocks, "larger stacks are refused").range(1, 100000));
    v(param("hold", hold, "frames a lost block is held").at_least(0));
    v(param("no-filter", no_filter, "publish raw detections"));
    v(param("scenario", scenario, "scenario file").existing_file());
    v(param("rate", rate, "frames per second").above_up_to(0, 1000));
    v(param("confirm", confirm, "seen in N of M frames, N/M").must([](const std::string& s) {
      return s.find('/') == std::string::npos ? std::string("must be N/M, e.g. 2/3") : std::string();
    }));
  }
};

ExampleConfig parse(std::vector<std::string> args) {
  ExampleConfig c;
  Flags flags("prog", "summary");
  declare_flags(flags, c);
  std::vector<const char*> argv{"prog"};
  for (const auto& a : args) argv.push_back(a.c_str());
  flags.parse(static_cast<int>(argv.size()), argv.data());
  read_flags(flags, c);
  return c;
}

std::string flag_error(std::vector<std::string> args) {
  try {
    parse(std::move(args));
  } catch (const FlagError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("flags come from the declaration: defaults, values, and --help with the rules") {
  ExampleConfig defaults = parse({});
  CHECK(defaults.annotator == "exact");
  CHECK(defaults.tolerance == 0.005);
  ExampleConfig c = parse({"--annotator=paper", "--tolerance", "0.01", "--max-blocks=60", "--no-filter"});
  CHECK(c.annotator == "paper");
  CHECK(c.tolerance == 0.01);
  CHECK(c.max_blocks == 60);
  CHECK(c.no_filter);

  ExampleConfig d;
  Flags flags("prog", "summary");
  declare_flags(flags, d);
  const std::string help = flags.help();
  CHECK(help.find("--tolerance=VALUE  block lengths [[0, 0.05]] (default: 0.005)") != std::string::npos);
  CHECK(help.find("[one of exact, paper, balance] (default: exact)") != std::string::npos);
  CHECK(help.find("--no-filter  publish raw detections") != std::string::npos);
}

TEST_CASE("a flag outside its rule is an error naming the flag, the rule and the value") {
  CHECK(flag_error({"--tolerance=0.2"}) == "--tolerance must be in [0, 0.05], got 0.2");
  CHECK(flag_error({"--annotator=magic"}) == "--annotator must be one of exact, paper, balance, got 'magic'");
  CHECK(flag_error({"--max-blocks=0"}) == "--max-blocks must be in [1, 100000], got 0");
  CHECK(flag_error({"--max-blocks=ten"}) == "--max-blocks expects an integer, got 'ten'");
  CHECK(flag_error({"--tolerance=nan"}) == "--tolerance expects a finite number, got 'nan'");
  CHECK(flag_error({"--hold=-1"}) == "--hold must be >= 0, got -1");
  CHECK(flag_error({"--confirm=23"}) == "--confirm must be N/M, e.g. 2/3");
  CHECK(flag_error({"--hold=99999999999"}) == "--hold expects an integer, got '99999999999'");
  CHECK(flag_error({"--rate=0"}) == "--rate must be in (0, 1000], got 0");
  CHECK(flag_error({"--rate=1000"}).empty());
}

TEST_CASE("a configuration built in code is checked by the same rules") {
  ExampleConfig c;
  CHECK_NOTHROW(validate(c));
  c.tolerance = -1;
  CHECK_THROWS_WITH(validate(c), "tolerance must be in [0, 0.05], got -1");
}

TEST_CASE("JSON: what a node records, read back strictly") {
  ExampleConfig c;
  c.annotator = "paper";
  const nlohmann::json j = to_json(c);
  CHECK(j["annotator"] == "paper");
  CHECK(j["max-blocks"] == 1000);
  ExampleConfig back;
  from_json(j, back);
  CHECK(back.annotator == "paper");
  CHECK(to_json(back) == j);
  CHECK_THROWS_WITH(from_json(nlohmann::json{{"anotator", "x"}}, back), Catch::Contains("unknown configuration key 'anotator'"));
  CHECK_THROWS_WITH(from_json(nlohmann::json{{"tolerance", "x"}}, back), "tolerance must be a finite number");
  CHECK_THROWS_WITH(from_json(nlohmann::json{{"tolerance", 1.0}}, back), "tolerance must be in [0, 0.05], got 1");
}

TEST_CASE("NAME=VALUE sets one field (a replay's --set)") {
  ExampleConfig c;
  set_from_text("annotator=balance", c);
  CHECK(c.annotator == "balance");
  set_from_text("no-filter=true", c);
  CHECK(c.no_filter);
  CHECK_THROWS_WITH(set_from_text("hold=x", c), "hold expects an integer, got 'x'");
  CHECK_THROWS_WITH(set_from_text("colour=red", c), Catch::Contains("unknown configuration key 'colour'"));
  CHECK_THROWS_AS(set_from_text("annotator", c), std::invalid_argument);
}

TEST_CASE("the declaration itself, and the files it names that are missing") {
  ExampleConfig c;
  const nlohmann::json d = describe(c);
  REQUIRE(d.size() == 8);
  CHECK(d[1]["name"] == "tolerance");
  CHECK(d[1]["min"] == 0.0);
  CHECK(d[1]["max"] == 0.05);
  CHECK(d[5]["file"] == true);
  CHECK(missing_paths(c).empty());  // "" names no file
  c.scenario = "/nonexistent/scenario.json";
  CHECK(missing_paths(c) == std::vector<std::string>{"--scenario: no such file '/nonexistent/scenario.json'"});
  harness::ScratchDir dir("config");
  harness::write_file(dir / "s.json", "{}");
  c.scenario = (dir / "s.json").string();
  CHECK(missing_paths(c).empty());
}

namespace {
struct WithArgument {
  std::string file;
  int rotate = 0;
  template <typename Visitor>
  void visit(Visitor& v) {
    v(param("FILE", file, "log file name").argument().must([](const std::string& f) {
      return f.empty() ? std::string("is empty") : std::string();
    }));
    v(param("rotate", rotate, "files kept").range(0, 100000));
  }
};
}  // namespace

TEST_CASE("a field can be an argument instead of a flag") {
  WithArgument c;
  Flags flags("prog", "summary");
  declare_flags(flags, c);
  const char* argv[] = {"prog", "--rotate", "3", "logs/day"};
  REQUIRE(flags.parse(4, argv));
  read_flags(flags, c);
  CHECK(c.file == "logs/day");
  CHECK(c.rotate == 3);
  CHECK(flags.help().find("arguments:\n  FILE  log file name") != std::string::npos);
  WithArgument d;
  Flags none("prog", "summary");
  declare_flags(none, d);
  const char* bare[] = {"prog"};
  CHECK_THROWS_AS(none.parse(1, bare), FlagError);  // a required argument
}
