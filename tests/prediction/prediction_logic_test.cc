// PredictionLogic without the bus: known answers, status mapping, determinism.
#include "bricklayer/prediction/prediction_logic.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "bricklayer/prediction/sample_stacks.h"

using namespace bricklayer;
using prediction::PredictionConfig;
using prediction::PredictionLogic;
using prediction::kUncertaintyFloor;

namespace {

stack_t one_block(double x, int64_t frame = 7) {
  stack_t s{};
  s.utime = 1'700'000'000'000'000 + frame;
  s.frame_number = frame;
  s.block_length = 1.0;
  s.block_height = 1.0 / 3.0;
  s.table_edge = 0.0;
  s.status = stack_t::STATUS_OK;
  block_t b{};
  b.id = 42;
  b.row = 0;
  b.x = x;
  b.confidence = 1.0;
  s.blocks.push_back(b);
  s.num_blocks = 1;
  return s;
}

template <typename T>
std::vector<uint8_t> bytes(const T& m) {
  std::vector<uint8_t> out(static_cast<size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

}  // namespace

TEST_CASE("a block with its centre over the surface stands, beyond the edge it is the cause") {
  PredictionLogic logic(PredictionConfig{});
  prediction_t stands = logic.answer(one_block(-0.6));
  CHECK(stands.status == prediction_t::STATUS_OK);
  CHECK(stands.error.empty());
  CHECK(stands.balanced);
  CHECK(stands.score == 40);
  REQUIRE(stands.num_blocks == 1);
  CHECK(stands.blocks[0].id == 42);
  CHECK(stands.blocks[0].state == block_prediction_t::STATE_STABLE);

  prediction_t falls = logic.answer(one_block(-0.4, 8));
  CHECK(falls.status == prediction_t::STATUS_OK);
  CHECK_FALSE(falls.balanced);
  CHECK(falls.overhang == Approx(0.6));
  CHECK(falls.score == 60);
  REQUIRE(falls.num_blocks == 1);
  CHECK(falls.blocks[0].state == block_prediction_t::STATE_CAUSE);
  CHECK(falls.annotator == "exact");
  CHECK_FALSE(falls.solver.empty());  // the core says what ran: "clp", "clp+nnls", "nnls", ...
}

TEST_CASE("every answer carries the utime and frame number of its stack") {
  PredictionLogic logic(PredictionConfig{});
  stack_t s = one_block(-0.6, 1234);
  s.utime = 987654321;
  prediction_t p = logic.answer(s);
  CHECK(p.utime == 987654321);
  CHECK(p.frame_number == 1234);
  s.status = stack_t::STATUS_NO_BOARD;
  p = logic.answer(s);
  CHECK(p.utime == 987654321);
  CHECK(p.frame_number == 1234);
}

TEST_CASE("a stack_t without a measurement is answered with STATUS_NO_STACK") {
  PredictionLogic logic(PredictionConfig{});
  for (int8_t status : {stack_t::STATUS_NO_FRAME, stack_t::STATUS_NO_BOARD}) {
    stack_t s = one_block(-0.6);
    s.status = status;
    s.blocks.clear();
    s.num_blocks = 0;
    prediction_t p = logic.answer(s);
    CHECK(p.status == prediction_t::STATUS_NO_STACK);
    CHECK_FALSE(p.error.empty());
    CHECK(p.num_blocks == 0);
  }
}

TEST_CASE("invalid stacks are answered with STATUS_INVALID_STACK and the core's reason") {
  PredictionConfig config;
  config.max_blocks = 20;
  PredictionLogic logic(config);

  SECTION("num_blocks disagrees with the blocks carried") {
    stack_t s = one_block(-0.6);
    s.num_blocks = 3;
    prediction_t p = logic.answer(s);
    CHECK(p.status == prediction_t::STATUS_INVALID_STACK);
    CHECK(p.error.find("num_blocks is 3") != std::string::npos);
    CHECK(p.blocks.empty());
  }
  SECTION("more blocks than --max-blocks") {
    prediction_t p = logic.answer(prediction::sample_stack(21, 1, 1, 1));
    CHECK(p.status == prediction_t::STATUS_INVALID_STACK);
    CHECK(p.error.find("21 blocks") != std::string::npos);
  }
  SECTION("a NaN coordinate") {
    stack_t s = one_block(std::numeric_limits<double>::quiet_NaN());
    prediction_t p = logic.answer(s);
    CHECK(p.status == prediction_t::STATUS_INVALID_STACK);
    CHECK_FALSE(p.error.empty());
  }
  SECTION("two blocks overlapping in one row") {
    stack_t s = one_block(-0.6);
    block_t b = s.blocks[0];
    b.id = 43;
    b.x = -0.2;
    s.blocks.push_back(b);
    s.num_blocks = 2;
    prediction_t p = logic.answer(s);
    CHECK(p.status == prediction_t::STATUS_INVALID_STACK);
    CHECK_FALSE(p.error.empty());
  }
  SECTION("duplicate ids") {
    stack_t s = one_block(-2.0);
    block_t b = s.blocks[0];
    b.x = -0.5;
    s.blocks.push_back(b);
    s.num_blocks = 2;
    prediction_t p = logic.answer(s);
    CHECK(p.status == prediction_t::STATUS_INVALID_STACK);
    CHECK(p.error.find("42") != std::string::npos);
  }
}

TEST_CASE("a failing core is a solver error with its message, not a crash") {
  auto failing = [](const core::Stack&, const std::vector<double>&, const core::PredictOptions&) -> core::KnifeEdgeVerdict {
    throw core::SolverError("balance LP (clp): numerical trouble");
  };
  PredictionLogic logic(PredictionConfig{}, failing);
  prediction_t p = logic.answer(one_block(-0.4));
  CHECK(p.status == prediction_t::STATUS_SOLVER_ERROR);
  CHECK(p.error == "balance LP (clp): numerical trouble");
  CHECK(p.num_blocks == 0);
  auto odd = [](const core::Stack&, const std::vector<double>&, const core::PredictOptions&) -> core::KnifeEdgeVerdict {
    throw std::bad_alloc();
  };
  PredictionLogic logic2(PredictionConfig{}, odd);
  CHECK(logic2.answer(one_block(-0.4)).status == prediction_t::STATUS_SOLVER_ERROR);
}

TEST_CASE("a bad configuration is rejected up front") {
  PredictionConfig config;
  config.annotator = "tarot";
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
  config.annotator = "exact";
  config.max_blocks = 0;
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
  config.max_blocks = 10;
  config.solver = "cplex";
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
  config.solver = "clp";
  config.position_tolerance = -0.001;
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
  config.position_tolerance = 0.5;
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
  config.position_tolerance = 0.0;
  config.uncertainty_floor = -0.001;
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
  config.uncertainty_floor = 0.2;
  CHECK_THROWS_AS(PredictionLogic(config), std::invalid_argument);
}

TEST_CASE("measured positions: stable, falls or knife edge with the floor, margin and deciding blocks") {
  PredictionLogic logic(PredictionConfig{});
  const double u = kUncertaintyFloor;
  // A single block's knife edge is its centre over the surface edge (x = -0.5); its margin is that distance.
  for (double past : {0.2 * u, 0.9 * u}) {
    INFO("centre " << past << " past the edge");
    const prediction_t p = logic.answer(one_block(-0.5 + past));
    CHECK(p.raw_verdict == prediction_t::VERDICT_KNIFE_EDGE);
    CHECK(p.verdict == prediction_t::VERDICT_KNIFE_EDGE);
    CHECK(p.balanced);  // not certain to fall: no red, the score counts
    CHECK(p.counts_for_max);
    CHECK(p.margin == Approx(-past).margin(1e-5));
    CHECK(p.margin_mm == Approx(-past * 75.0).margin(1e-3));
    CHECK(p.blocks.at(0).state == block_prediction_t::STATE_STABLE);
    CHECK(p.blocks.at(0).deciding);
    const prediction_t in = logic.answer(one_block(-0.5 - past));
    CHECK(in.raw_verdict == prediction_t::VERDICT_KNIFE_EDGE);
    CHECK(in.margin == Approx(past).margin(1e-6));
    CHECK(in.blocks.at(0).deciding);  // the cause if it fell
  }
  const prediction_t over = logic.answer(one_block(-0.5 + 1.5 * u));
  CHECK(over.raw_verdict == prediction_t::VERDICT_FALLS);
  CHECK_FALSE(over.balanced);
  CHECK_FALSE(over.counts_for_max);
  CHECK(over.blocks.at(0).state == block_prediction_t::STATE_CAUSE);
  CHECK(over.margin <= -u);
  const prediction_t stands = logic.answer(one_block(-0.5 - 1.5 * u));
  CHECK(stands.raw_verdict == prediction_t::VERDICT_STABLE);
  CHECK(stands.margin == Approx(1.5 * u).margin(1e-6));
  CHECK_FALSE(stands.blocks.at(0).deciding);
  CHECK(stands.uncertainty == u);
  CHECK(stands.uncertainty_floor == u);
  CHECK(stands.blocks.at(0).uncertainty == u);
  CHECK(stands.position_tolerance == 0.0);
  bricklayer::stack_t none = one_block(-0.6);
  none.status = bricklayer::stack_t::STATUS_NO_FRAME;
  const prediction_t failed = logic.answer(none);
  CHECK(failed.uncertainty_floor == u);  // failures say the configuration too
  CHECK(failed.verdict == prediction_t::VERDICT_KNIFE_EDGE);
  CHECK_FALSE(failed.counts_for_max);
}

TEST_CASE("vision's own uncertainty counts when above the floor, a bad one is an invalid stack") {
  PredictionLogic logic(PredictionConfig{});
  bricklayer::stack_t s = one_block(-0.5 - 0.008);  // 0.008 inside: stable with the floor ...
  CHECK(logic.answer(s).raw_verdict == prediction_t::VERDICT_STABLE);
  s.blocks[0].x_uncertainty = 0.01;  // ... a knife edge when vision says +-0.01
  const prediction_t p = logic.answer(s);
  CHECK(p.raw_verdict == prediction_t::VERDICT_KNIFE_EDGE);
  CHECK(p.uncertainty == 0.01);
  CHECK(p.blocks.at(0).uncertainty == 0.01);
  s.blocks[0].x_uncertainty = 1.0;  // capped at the core's limit
  CHECK(logic.answer(s).uncertainty == core::kMaxUncertainty);
  for (double bad : {-0.001, std::numeric_limits<double>::quiet_NaN()}) {
    s.blocks[0].x_uncertainty = bad;
    const prediction_t q = logic.answer(s);
    CHECK(q.status == prediction_t::STATUS_INVALID_STACK);
    CHECK(q.error.find("x_uncertainty") != std::string::npos);
  }
  PredictionConfig exact;
  exact.uncertainty_floor = 0.0;  // no floor, vision silent: the exact verdict
  CHECK(PredictionLogic(exact).answer(one_block(-0.5 + 0.0005)).raw_verdict == prediction_t::VERDICT_FALLS);
}

TEST_CASE("the legacy widening still answers stable or falls, never a knife edge") {
  PredictionConfig legacy;
  legacy.position_tolerance = 0.005;
  PredictionLogic logic(legacy);
  const prediction_t p = logic.answer(one_block(-0.5 + 0.0045));
  CHECK(p.raw_verdict == prediction_t::VERDICT_STABLE);
  CHECK(p.position_tolerance == 0.005);
  CHECK(logic.answer(one_block(-0.5 + 0.0075)).raw_verdict == prediction_t::VERDICT_FALLS);
}

TEST_CASE("answers are a pure function of the stack: same bytes every time, for every annotator") {
  for (std::string annotator : {"exact", "paper", "balance"}) {
    PredictionConfig config;
    config.annotator = annotator;
    PredictionLogic a(config), b(config);
    for (uint32_t seed = 1; seed <= 20; ++seed) {
      stack_t s = prediction::sample_stack(25, seed, seed, seed);
      auto first = bytes(a.answer(s));
      (void)b.answer(prediction::sample_stack(60, seed + 100, 0, 0));  // unrelated work in between
      CHECK(bytes(b.answer(s)) == first);
      CHECK(bytes(a.answer(s)) == first);
    }
  }
}

TEST_CASE("the LP backend named by a recorded solver field") {
  CHECK(prediction::lp_backend_of("clp") == "clp");
  CHECK(prediction::lp_backend_of("clp+nnls") == "clp");
  CHECK(prediction::lp_backend_of("nlopt+nnls") == "nlopt");
  CHECK(prediction::lp_backend_of("nnls").empty());
  CHECK(prediction::lp_backend_of("").empty());
}

TEST_CASE("the sample stacks are valid piles and deterministic") {
  PredictionLogic logic(PredictionConfig{});
  for (int n : {1, 2, 25, 60, 200}) {
    stack_t s = prediction::sample_stack(n, 9, 0, 0);
    CHECK(s.num_blocks == n);
    CHECK(bytes(s) == bytes(prediction::sample_stack(n, 9, 0, 0)));
    CHECK(logic.answer(s).status == prediction_t::STATUS_OK);
  }
}
