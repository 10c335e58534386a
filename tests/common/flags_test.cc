#include "bricklayer/common/flags.h"

#include <catch2/catch.hpp>

using bricklayer::FlagError;
using bricklayer::Flags;

namespace {
Flags make() {
  Flags f("prog", "does things");
  f.add("rate", "10", "frames per second");
  f.add_bool("json", "print JSON");
  f.add_positional("FILE", "input", true);
  return f;
}
}  // namespace

TEST_CASE("flags parse both value spellings, booleans and positionals") {
  Flags f = make();
  const char* argv[] = {"prog", "--rate=30", "--json", "in.json"};
  REQUIRE(f.parse(4, argv));
  CHECK(f.get_int("rate") == 30);
  CHECK(f.get_bool("json"));
  REQUIRE(f.positional().size() == 1);
  CHECK(f.positional()[0] == "in.json");

  Flags g = make();
  const char* argv2[] = {"prog", "--rate", "5", "-"};
  REQUIRE(g.parse(4, argv2));
  CHECK(g.get_int("rate") == 5);
  CHECK_FALSE(g.get_bool("json"));
  CHECK(g.positional()[0] == "-");
}

TEST_CASE("flags reject unknown flags, missing values and missing arguments with a fix") {
  Flags f = make();
  const char* unknown[] = {"prog", "--speed=3", "x"};
  CHECK_THROWS_WITH(f.parse(3, unknown), Catch::Contains("unknown flag --speed"));
  Flags g = make();
  const char* missing_value[] = {"prog", "x", "--rate"};
  CHECK_THROWS_WITH(g.parse(3, missing_value), Catch::Contains("needs a value"));
  Flags h = make();
  const char* missing_arg[] = {"prog", "--json"};
  CHECK_THROWS_WITH(h.parse(2, missing_arg), Catch::Contains("expected 1 argument"));
  Flags k = make();
  const char* bad_int[] = {"prog", "--rate=fast", "x"};
  REQUIRE(k.parse(3, bad_int));
  CHECK_THROWS_WITH(k.get_int("rate"), Catch::Contains("expects an integer"));
}

TEST_CASE("a positional list takes one or more values, and only one positional takes none more") {
  Flags f("prog", "reads logs");
  f.add("out", "", "folder");
  f.add_positional_list("LOG", "log files");
  const char* argv[] = {"prog", "a.0", "--out", "dir", "a.1", "a.2"};
  REQUIRE(f.parse(6, argv));
  CHECK(f.positional() == std::vector<std::string>{"a.0", "a.1", "a.2"});
  CHECK(f.get("out") == "dir");
  CHECK_THAT(f.help(), Catch::Contains("LOG..."));
  Flags none("prog", "reads logs");
  none.add_positional_list("LOG", "log files");
  const char* empty[] = {"prog"};
  CHECK_THROWS_WITH(none.parse(1, empty), Catch::Contains("expected 1 argument"));
  Flags single = make();
  const char* two[] = {"prog", "a", "b"};
  CHECK_THROWS_WITH(single.parse(3, two), Catch::Contains("unexpected argument 'b'"));
}

TEST_CASE("--help prints usage and asks the caller to exit") {
  Flags f = make();
  const char* argv[] = {"prog", "--help"};
  CHECK_FALSE(f.parse(2, argv));
  CHECK_THAT(f.help(), Catch::Contains("--rate=VALUE") && Catch::Contains("default: 10"));
}
