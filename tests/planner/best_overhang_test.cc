// The best-overhang optimiser and the table it wrote (modules/planner/data).
#include "bricklayer/planner/best_overhang.h"

#include <catch2/catch.hpp>

#include <fstream>

#include <nlohmann/json.hpp>

#include "bricklayer/core/predict.h"

using namespace bricklayer;

namespace {

nlohmann::json load(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  return nlohmann::json::parse(in);
}

const std::string kData = std::string(BRICKLAYER_SOURCE_DIR) + "/modules/planner/data/";

// Paterson & Zwick's optima (shared fixtures/optimal-stacks.json).
const double kKnown[] = {0.0, 0.5, 0.75, 1.0, 1.16789321881, 1.30455, 1.4367};

}  // namespace

TEST_CASE("the optimiser reproduces the known optima for n = 1..6") {
  const auto best = planner::search_best_overhang(6);
  REQUIRE(best.size() == 6);
  for (int n = 1; n <= 6; ++n) {
    INFO("n = " << n);
    CHECK(best[n - 1].overhang == Approx(kKnown[n]).margin(1e-4));
    CHECK(best[n - 1].blocks.size() == static_cast<size_t>(n));
    CHECK(best[n - 1].residual < 1e-9);
  }
}

TEST_CASE("a single layout optimisation finds the 4-block optimum (15 - 4 sqrt 2) / 8") {
  const std::vector<planner::PlacedBlock> start = {{0, -0.5}, {1, -1.0}, {1, 0.1}, {2, -0.6}};
  const auto s = planner::optimise_layout(start, 2);
  REQUIRE(s);
  CHECK(s->overhang == Approx((15.0 - 4.0 * std::sqrt(2.0)) / 8.0).margin(1e-7));
}

TEST_CASE("the shipped table has the known values and what we reached at n = 30") {
  const nlohmann::json table = load(kData + "best_overhang.json");
  for (int n = 1; n <= 30; ++n) REQUIRE(table.contains(std::to_string(n)));
  for (int n = 3; n <= 6; ++n) CHECK(table[std::to_string(n)].get<double>() == Approx(kKnown[n]).margin(1e-4));
  // Issue 7 asks for >= 2.70 (published optimum 2.70909); this optimiser reached 2.553856 (see README).
  CHECK(table["30"].get<double>() >= 2.55);
  for (int n = 2; n <= 30; ++n)  // one more block never reaches less
    CHECK(table[std::to_string(n)].get<double>() >= table[std::to_string(n - 1)].get<double>() - 1e-12);
}

TEST_CASE("every shipped stack is balanced by the exact annotator and reaches its table value") {
  const nlohmann::json table = load(kData + "best_overhang.json");
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  for (int n = 1; n <= 30; ++n) {
    INFO("n = " << n);
    const auto& entry = stacks.at(std::to_string(n));
    core::Stack s;
    int64_t id = 1;
    for (const auto& b : entry.at("blocks")) s.blocks.push_back({id++, b.at("row").get<int>(), b.at("x").get<double>()});
    REQUIRE(s.blocks.size() == static_cast<size_t>(n));
    const core::Prediction p = core::predict(s);
    CHECK(p.balanced);
    CHECK(p.overhang == Approx(table[std::to_string(n)].get<double>()).margin(1e-6));
  }
}
