// The best-overhang optimiser and the table it wrote (modules/planner/data).
#include "bricklayer/planner/best_overhang.h"

#include <algorithm>
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <limits>
#include <random>

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

// Paterson & Zwick's published optima (tests/data/optimal-stacks.json, a copy of the shared fixture).
double published(int n) {
  static const nlohmann::json fixture = load(std::string(BRICKLAYER_SOURCE_DIR) + "/tests/data/optimal-stacks.json");
  return fixture.at("max_overhang").at(std::to_string(n)).get<double>();
}

// A stack as the stacks file holds it ({"overhang", "residual", "blocks": [{"row", "x"}...]}).
planner::OverhangStack stack_from_json(const nlohmann::json& entry) {
  planner::OverhangStack s;
  s.overhang = entry.at("overhang").get<double>();
  s.residual = entry.at("residual").get<double>();
  for (const auto& b : entry.at("blocks")) s.blocks.push_back({b.at("row").get<int>(), b.at("x").get<double>()});
  return s;
}

planner::OverhangStack shipped_stack(const nlohmann::json& stacks, int n) {
  return stack_from_json(stacks.at(std::to_string(n)));
}

int rightmost(const std::vector<planner::PlacedBlock>& blocks) {
  int best = 0;
  for (size_t i = 1; i < blocks.size(); ++i)
    if (blocks[i].x > blocks[best].x) best = static_cast<int>(i);
  return best;
}

}  // namespace

TEST_CASE("the optimiser reproduces the known optima for n = 1..6") {
  const auto best = planner::search_best_overhang(6);
  REQUIRE(best.size() == 6);
  for (int n = 1; n <= 6; ++n) {
    INFO("n = " << n);
    CHECK(best[n - 1].overhang == Approx(published(n)).margin(1e-4));
    CHECK(best[n - 1].blocks.size() == static_cast<size_t>(n));
    CHECK(best[n - 1].residual < 1e-9);
  }
}

TEST_CASE("a single layout optimisation finds the 4-block optimum (15 - 4 sqrt 2) / 8") {
  const std::vector<planner::PlacedBlock> start = {{0, -0.5}, {1, -1.0}, {1, 0.1}, {2, -0.6}};
  const auto s = planner::optimise_layout(start, 2);
  REQUIRE(s);
  CHECK(s->overhang == Approx((15.0 - 4.0 * std::sqrt(2.0)) / 8.0).margin(1e-7));
  CHECK(s->residual < 1e-9);
}

TEST_CASE("from the 30-block layout shaken out of balance, the optimiser climbs back to the published 2.70909") {
  // Only the rows (the combinatorial type) come from the shipped stack; every position is moved by up to a
  // tenth of a block, which leaves the stack far from balanced. The answer must be the published optimum.
  const planner::OverhangStack best = shipped_stack(load(kData + "best_overhang_stacks.json"), 30);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> shake(-0.1, 0.1);
  for (int trial = 0; trial < 3; ++trial) {
    INFO("trial " << trial);
    std::vector<planner::PlacedBlock> start = best.blocks;
    for (planner::PlacedBlock& b : start) b.x += shake(rng);
    const auto s = planner::optimise_layout(start, rightmost(start));
    REQUIRE(s);
    CHECK(s->overhang == Approx(published(30)).margin(1e-5));
    CHECK(s->residual < 1e-9);
  }
}

TEST_CASE("the search grows the 19-block optimum into the 20-block one (the first non-spinal size)") {
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  planner::OverhangSearchOptions options;
  options.beam = 1;  // one layout, no restarts or wall starts: the growth step alone
  options.perturbations = 0;
  options.wall_seeds = 0;
  options.shrink = false;
  for (int n = 1; n <= 19; ++n) options.resume_from.push_back(shipped_stack(stacks, n));
  const auto best = planner::search_best_overhang(20, options);
  REQUIRE(best.size() == 20);
  const planner::OverhangStack& s = best.back();
  CHECK(s.blocks.size() == 20);
  CHECK(s.overhang > best[18].overhang + 0.04);
  // Growth alone reaches 2.318994 (the table's value until the shrink step found 2.320136 from n = 22).
  CHECK(s.overhang >= 2.318994 - 1e-6);
  CHECK(s.overhang <= stacks.at("20").at("overhang").get<double>() + 1e-9);
  CHECK(s.residual < 1e-9);
}

TEST_CASE("from scratch, the default search reaches the shipped table at every n up to 15") {
  // The shipped rows 1..30 must be reproducible from n = 1 by this tree. A beam of 6 (the width the table
  // used to be made with) falls behind here: 2.08713 at n = 15 instead of 2.092896.
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  planner::OverhangSearchOptions options;
  options.jobs = 2;  // the answer does not depend on it (next test)
  const auto best = planner::search_best_overhang(15, options);
  REQUIRE(best.size() == 15);
  for (int n = 1; n <= 15; ++n) {
    INFO("n = " << n);
    CHECK(best[n - 1].blocks.size() == static_cast<size_t>(n));
    CHECK(best[n - 1].overhang >= stacks.at(std::to_string(n)).at("overhang").get<double>() - 1e-6);
    CHECK(best[n - 1].residual < 1e-9);
    CHECK(planner::annotator_balanced(best[n - 1]));
  }
}

TEST_CASE("the search writes a row only when the exact annotator calls it balanced") {
  // A stack the optimiser balanced (LP residual 1e-14) that the annotator's default QP reads as moving (contacts
  // overlapping by the 1e-4 minimum): annotator_balanced refuses it, and the row shipped for its n passes.
  // Without the check a run shipped it as row 51.
  const planner::OverhangStack read_moving =
      stack_from_json(load(std::string(BRICKLAYER_SOURCE_DIR) + "/tests/data/overhang_stack_read_moving.json"));
  core::Stack stack;
  int64_t id = 1;
  for (const planner::PlacedBlock& b : read_moving.blocks) stack.blocks.push_back({id++, b.row, b.x});
  REQUIRE(read_moving.blocks.size() == 51);
  CHECK_FALSE(planner::annotator_balanced(read_moving));
  CHECK_FALSE(core::predict(stack).balanced);
  core::PredictOptions nlopt;
  nlopt.qp = core::QpMethod::kNlopt;
  CHECK(core::predict(stack, nlopt).balanced);  // the stack is balanced; the default QP's rounding is not
  // The search later found another 51-block stack of the same overhang (to 1e-9) that the annotator reads
  // balanced; that one is shipped.
  const planner::OverhangStack shipped = shipped_stack(load(kData + "best_overhang_stacks.json"), 51);
  CHECK(planner::annotator_balanced(shipped));
  CHECK(shipped.overhang == Approx(read_moving.overhang).margin(1e-9));
  bool same_positions = true;
  for (size_t i = 0; i < shipped.blocks.size(); ++i)
    same_positions = same_positions && shipped.blocks[i].x == read_moving.blocks[i].x;
  CHECK_FALSE(same_positions);
}

TEST_CASE("the search gives the same stacks, to the last bit, on one thread and on several") {
  // The table's generator runs on every core; its files must still be the one-thread search's.
  planner::OverhangSearchOptions one, several;
  several.jobs = 3;
  // n = 10: past 8, where the brick-wall starts join (350 s under the sanitizers at 12, so not larger).
  // The beam (default: one stack of each overhang) never holds one stack twice over.
  int beams = 0;
  const auto a = planner::search_best_overhang(10, one, {}, [&](const planner::OverhangSearchState& state) {
    ++beams;
    INFO("n = " << state.best_per_n.size());
    CHECK(!state.beam.empty());
    CHECK(state.beam.size() <= 8);
    for (size_t i = 0; i < state.beam.size(); ++i)
      for (size_t j = 0; j < i; ++j) CHECK(std::abs(state.beam[i].overhang - state.beam[j].overhang) > 1e-9);
  });
  CHECK(beams == 9);
  const auto b = planner::search_best_overhang(10, several);
  REQUIRE(a.size() == b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    INFO("n = " << k + 1);
    CHECK(a[k].overhang == b[k].overhang);
    CHECK(a[k].residual == b[k].residual);
    REQUIRE(a[k].blocks.size() == b[k].blocks.size());
    for (size_t i = 0; i < a[k].blocks.size(); ++i) {
      CHECK(a[k].blocks[i].row == b[k].blocks[i].row);
      CHECK(a[k].blocks[i].x == b[k].blocks[i].x);
    }
  }
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  const auto less_one = planner::best_one_block_less(shipped_stack(stacks, 23));
  const auto less_several = planner::best_one_block_less(shipped_stack(stacks, 23), 1e-9, 4);
  REQUIRE(less_one);
  REQUIRE(less_several);
  CHECK(less_one->overhang == less_several->overhang);
  REQUIRE(less_one->blocks.size() == less_several->blocks.size());
  for (size_t i = 0; i < less_one->blocks.size(); ++i) CHECK(less_one->blocks[i].x == less_several->blocks[i].x);
}

TEST_CASE("one-block moves give the same stacks on one thread and on several") {
  // The moves run several at a time; the first improving one in the seeded order must still be the one taken.
  planner::OverhangSearchOptions one, several;
  one.moves = several.moves = 40;
  several.jobs = 3;
  const auto a = planner::search_best_overhang(9, one);
  const auto b = planner::search_best_overhang(9, several);
  REQUIRE(a.size() == b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    INFO("n = " << k + 1);
    CHECK(a[k].overhang == b[k].overhang);
    REQUIRE(a[k].blocks.size() == b[k].blocks.size());
    for (size_t i = 0; i < a[k].blocks.size(); ++i) CHECK(a[k].blocks[i].x == b[k].blocks[i].x);
  }
}

TEST_CASE("without a limit on alike stacks the beam fills with one stack's counterweights rearranged") {
  // Why the limit exists: at n = 7 the eight layouts kept reach only six overhangs (n = 13: all eight the same
  // stack, its top blocks arranged as 1,1,1 or 2,1 or 3).
  planner::OverhangSearchOptions options;
  options.alike = 0;
  options.jobs = 2;
  std::vector<double> beam;
  planner::search_best_overhang(7, options, {}, [&](const planner::OverhangSearchState& state) {
    beam.clear();
    for (const auto& s : state.beam) beam.push_back(s.overhang);
  });
  REQUIRE(beam.size() == 8);
  std::sort(beam.begin(), beam.end());
  const auto distinct = std::unique(beam.begin(), beam.end(), [](double x, double y) { return std::abs(x - y) <= 1e-9; });
  CHECK(distinct - beam.begin() < 8);
}

TEST_CASE("from variety_from on, the beam also keeps the best layout of load rows it lacks") {
  // The row of the rightmost block (the load point): stacks with it higher start behind and overtake later.
  auto load_row = [](const planner::OverhangStack& s) {
    return std::max_element(s.blocks.begin(), s.blocks.end(), [](const auto& a, const auto& b) { return a.x < b.x; })->row;
  };
  planner::OverhangSearchOptions options;
  options.jobs = 2;
  options.variety = 3;
  options.variety_from = 9;
  int widened = 0;
  planner::search_best_overhang(10, options, {}, [&](const planner::OverhangSearchState& state) {
    const size_t n = state.best_per_n.size();
    INFO("n = " << n);
    if (n < 9) {
      CHECK(state.beam.size() <= 8);
      return;
    }
    REQUIRE(state.beam.size() <= 8 + 3);
    std::set<int> rows;
    for (size_t i = 0; i < std::min<size_t>(8, state.beam.size()); ++i) rows.insert(load_row(state.beam[i]));
    for (size_t i = 8; i < state.beam.size(); ++i) {
      CHECK(rows.insert(load_row(state.beam[i])).second);  // a row none before it has
      CHECK(state.beam[i].overhang <= state.beam[7].overhang);
      ++widened;
    }
  });
  CHECK(widened > 0);
}

TEST_CASE("one block less: the shipped 23-block stack minus a block is the shipped 22-block optimum") {
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  const auto s = planner::best_one_block_less(shipped_stack(stacks, 23));
  REQUIRE(s);
  CHECK(s->blocks.size() == 22);
  CHECK(s->overhang >= stacks.at("22").at("overhang").get<double>() - 1e-6);
  CHECK(s->residual < 1e-9);
  CHECK_FALSE(planner::best_one_block_less(shipped_stack(stacks, 1)));
}

TEST_CASE("the search takes the best n stack minus a block for n-1 when that is better (shrink)") {
  // Resumed at 19, growth alone (beam 1) reaches 2.318994 at 20, less than the shipped 2.320136, which
  // was found by shrinking from 22: the shipped 22-block stack, given as a start layout at 22, minus
  // blocks is better for 21 and then 20, and the search must take them.
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  const double shipped20 = stacks.at("20").at("overhang").get<double>();
  const double shipped21 = stacks.at("21").at("overhang").get<double>();
  planner::OverhangSearchOptions options;
  options.beam = 1;
  options.perturbations = 0;
  options.wall_seeds = 0;
  for (int n = 1; n <= 19; ++n) options.resume_from.push_back(shipped_stack(stacks, n));
  options.start_layouts.resize(22);
  options.start_layouts[21] = shipped_stack(stacks, 22);
  options.shrink = false;
  const auto grown_only = planner::search_best_overhang(22, options);
  REQUIRE(grown_only.size() == 22);
  CHECK(grown_only[19].overhang < shipped20 - 1e-4);
  std::vector<int> reported;
  options.shrink = true;
  const auto best = planner::search_best_overhang(22, options, [&](int n, const planner::OverhangStack& s) {
    if (n > 19) reported.push_back(n);
    CHECK(s.blocks.size() == static_cast<size_t>(n));
  });
  REQUIRE(best.size() == 22);
  CHECK(best[19].overhang >= shipped20 - 1e-6);
  CHECK(best[20].overhang >= shipped21 - 1e-6);
  CHECK(best[21].overhang >= best[20].overhang);
  for (int n = 1; n <= 19; ++n) CHECK(best[n - 1].overhang == options.resume_from[n - 1].overhang);  // kept as given
  CHECK(std::count(reported.begin(), reported.end(), 20) >= 2);  // 20 again once a larger stack improved it
  CHECK(reported.back() == 22);
}

TEST_CASE("bad layouts get a clear error or no answer, never a crash") {
  CHECK_FALSE(planner::optimise_layout({}, 0));
  CHECK_THROWS_WITH(planner::optimise_layout({{0, -0.5}}, 1), Catch::Contains("target 1 out of range"));
  CHECK_THROWS_WITH(planner::optimise_layout({{0, std::numeric_limits<double>::quiet_NaN()}}, 0),
                    Catch::Contains("finite"));
  CHECK_THROWS_WITH(planner::optimise_layout({{0, -0.5}, {2, -0.5}}, 0), Catch::Contains("no row below"));
  CHECK_THROWS_WITH(planner::search_best_overhang(0), Catch::Contains("at least 1"));
  // A block far beyond the edge with nothing to balance it: infeasible, so no answer.
  CHECK_FALSE(planner::optimise_layout({{0, 5.0}}, 0));
}

TEST_CASE("the shipped table has the known values, reaches 2.70 at n = 30, covers the board's 60 blocks and never falls with n") {
  const nlohmann::json table = load(kData + "best_overhang.json");
  const int largest = static_cast<int>(table.size());
  REQUIRE(largest >= 60);
  for (int n = 1; n <= largest; ++n) REQUIRE(table.contains(std::to_string(n)));  // 1..largest, no gaps
  for (int n = 3; n <= 6; ++n) CHECK(table[std::to_string(n)].get<double>() == Approx(published(n)).margin(1e-4));
  const double at30 = table["30"].get<double>();
  CHECK(at30 >= 2.70);
  CHECK(at30 <= published(30) + 1e-5);  // the published optimum: more would mean a wrong model
  for (int n = 2; n <= largest; ++n)  // one more block never reaches less
    CHECK(table[std::to_string(n)].get<double>() >= table[std::to_string(n - 1)].get<double>() - 1e-12);
}

TEST_CASE("every shipped stack is balanced by the exact annotator and reaches its table value") {
  const nlohmann::json table = load(kData + "best_overhang.json");
  const nlohmann::json stacks = load(kData + "best_overhang_stacks.json");
  REQUIRE(stacks.size() == table.size());
  for (int n = 1; n <= static_cast<int>(table.size()); ++n) {
    INFO("n = " << n);
    const auto& entry = stacks.at(std::to_string(n));
    core::Stack s;
    int64_t id = 1;
    for (const auto& b : entry.at("blocks")) s.blocks.push_back({id++, b.at("row").get<int>(), b.at("x").get<double>()});
    REQUIRE(s.blocks.size() == static_cast<size_t>(n));
    const core::Prediction p = core::predict(s);
    CHECK(p.balanced);
    CHECK(p.overhang == Approx(table[std::to_string(n)].get<double>()).margin(1e-6));
    CHECK(entry.at("residual").get<double>() < 1e-9);
  }
}

TEST_CASE("the planner's linear programs go through the core's solver adapter, not a solver library") {
  // One problem description and one status vocabulary for every LP of the project: no planner source talks
  // to CLP (or another solver) directly.
  const std::filesystem::path root = std::filesystem::path(BRICKLAYER_SOURCE_DIR) / "modules/planner";
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".cc" && ext != ".h" && entry.path().filename() != "CMakeLists.txt") continue;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    INFO(entry.path().string());
    for (const char* direct : {"ClpSimplex", "CoinPackedMatrix", "PkgConfig::CLP", "glpk.h", "nlopt.hpp"})
      CHECK(text.str().find(direct) == std::string::npos);
    ++files;
  }
  CHECK(files >= 8);
  std::ifstream optimiser(root / "src/best_overhang.cc");
  std::stringstream text;
  text << optimiser.rdbuf();
  CHECK(text.str().find("bricklayer/core/program.h") != std::string::npos);
}
