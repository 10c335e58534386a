#include "bricklayer/projection/best_overhang.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

using namespace bricklayer::projection;

TEST_CASE("the best-overhang table is read by block count") {
  BestOverhang t = BestOverhang::parse(R"({"1": 0.5, "2": 0.75, "30": 2.70909})");
  CHECK(t.size() == 3);
  CHECK(*t.best_for(1) == 0.5);
  CHECK(*t.best_for(30) == Approx(2.70909));
  CHECK_FALSE(t.best_for(3));
  CHECK(t.largest() == 30);
  CHECK(BestOverhang{}.largest() == 0);
  CHECK_FALSE(t.best_for(0));
}

TEST_CASE("a bad table says what is wrong") {
  CHECK_THROWS_WITH(BestOverhang::parse("[1,2]"), Catch::Contains("object"));
  CHECK_THROWS_WITH(BestOverhang::parse(R"({"two": 0.75})"), Catch::Contains("'two'"));
  CHECK_THROWS_WITH(BestOverhang::parse(R"({"2": -1})"), Catch::Contains("positive"));
  CHECK_THROWS_WITH(BestOverhang::parse("{"), Catch::Contains("JSON"));
  CHECK_THROWS_WITH(BestOverhang::load("/nonexistent/best_overhang.json"), Catch::Contains("cannot read"));
}

TEST_CASE("the planner's table, when it exists, parses and grows with n") {
  const std::filesystem::path path = std::filesystem::path(BRICKLAYER_SOURCE_DIR) / "modules/planner/data/best_overhang.json";
  if (!std::filesystem::exists(path)) {
    WARN("no " << path << " yet");
    return;
  }
  BestOverhang t = BestOverhang::load(path.string());
  REQUIRE(t.best_for(1));
  CHECK(*t.best_for(1) == Approx(0.5));
  for (int n = 2; n <= 30; ++n)
    if (t.best_for(n) && t.best_for(n - 1)) CHECK(*t.best_for(n) >= *t.best_for(n - 1));
}
