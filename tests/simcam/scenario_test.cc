#include "bricklayer/simcam/scenario.h"

#include <catch2/catch.hpp>

#include "bricklayer/core/predict.h"

using namespace bricklayer;

TEST_CASE("a scenario shows the last key frame at or before t") {
  auto s = simcam::parse_scenario(R"({"nuisance": "mild", "seed": 3, "keyframes": [
      {"t": 0, "blocks": []},
      {"t": 2, "blocks": [{"id": 1, "row": 0, "x": -0.5}]},
      {"t": 4.5, "blocks": [{"id": 1, "row": 0, "x": -0.5}, {"id": 2, "row": 1, "x": -0.2}]}]})");
  CHECK(s.seed == 3);
  CHECK(s.nuisance.name == "mild");
  CHECK(s.duration_s == Approx(9.5));
  CHECK(s.stack_at(0.0).blocks.empty());
  CHECK(s.stack_at(1.99).blocks.empty());
  CHECK(s.stack_at(2.0).blocks.size() == 1);
  CHECK(s.stack_at(100.0).blocks.size() == 2);
}

TEST_CASE("bad scenarios are rejected with a message naming the problem") {
  CHECK_THROWS_WITH(simcam::parse_scenario("{", "s.json"), Catch::Contains("s.json: not valid JSON"));
  CHECK_THROWS_WITH(simcam::parse_scenario(R"({"keyframes": []})"), Catch::Contains("non-empty array"));
  CHECK_THROWS_WITH(simcam::parse_scenario(R"({"keyframes": [{"t": 0}], "speed": 2})"),
                    Catch::Contains("unknown key 'speed'"));
  CHECK_THROWS_WITH(simcam::parse_scenario(R"({"keyframes": [{"t": 1}, {"t": 1}]})"),
                    Catch::Contains("key frame 1") && Catch::Contains("later than the previous"));
  CHECK_THROWS_WITH(simcam::parse_scenario(R"({"nuisance": "foggy", "keyframes": [{"t": 0}]})"),
                    Catch::Contains("foggy"));
  CHECK_THROWS_WITH(
      simcam::parse_scenario(R"({"keyframes": [{"t": 0, "blocks": [{"id": 1, "row": 0, "x": "left"}]}]})"),
      Catch::Contains("key frame 0"));
  CHECK_THROWS_WITH(simcam::parse_scenario(R"({"duration_s": 1, "keyframes": [{"t": 0}, {"t": 2}]})"),
                    Catch::Contains("'duration_s' must be later"));
}

namespace {
std::vector<std::pair<bool, std::vector<int64_t>>> verdicts(const std::string& file) {
  auto s = simcam::load_scenario(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/" + file);
  std::vector<std::pair<bool, std::vector<int64_t>>> out;
  for (const auto& k : s.keyframes) {
    if (k.stack.blocks.empty()) continue;
    auto p = core::predict(k.stack);
    out.emplace_back(p.balanced, p.causes());
  }
  return out;
}
}  // namespace

TEST_CASE("the bundled scenarios do what their descriptions say") {
  // build-4-optimum: balanced, balanced, right block red without its counterweight, balanced, the optimum,
  // the counterweight lifted, the optimum again, pushed too far, the optimum again.
  auto build = verdicts("build-4-optimum.json");
  REQUIRE(build.size() == 9);
  CHECK(build[0].first);
  CHECK(build[1].first);
  CHECK_FALSE(build[2].first);
  CHECK(build[2].second == std::vector<int64_t>{3});
  CHECK(build[4].first);
  CHECK_FALSE(build[5].first);
  CHECK(build[6].first);
  CHECK_FALSE(build[7].first);
  CHECK(build[8].first);
  auto optimum = simcam::load_scenario(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/build-4-optimum.json");
  CHECK(core::score_of(core::overhang(optimum.stack_at(12.0))) == 117);

  // wall-60: balanced at every step, 60 blocks at the end.
  auto wall = verdicts("wall-60.json");
  for (const auto& [balanced, causes] : wall) CHECK(balanced);
  auto w = simcam::load_scenario(std::string(BRICKLAYER_SOURCE_DIR) + "/launch/scenarios/wall-60.json");
  CHECK(w.keyframes.back().stack.blocks.size() == 60);

  // collapse: balanced while it grows, then unbalanced, then a smaller balanced pile after the fall.
  auto collapse = verdicts("collapse.json");
  CHECK(collapse.front().first);
  bool saw_unbalanced = false;
  for (const auto& v : collapse) saw_unbalanced |= !v.first;
  CHECK(saw_unbalanced);
  CHECK(collapse.back().first);
}
