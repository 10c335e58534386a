// PredictionLogic without the bus: known answers, status mapping, determinism.
#include "bricklayer/prediction/prediction_logic.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "bricklayer/prediction/sample_stacks.h"

using namespace bricklayer;
using prediction::PredictionConfig;
using prediction::PredictionLogic;
using prediction::kMeasuredPositionTolerance;

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
  auto failing = [](const core::Stack&, const core::PredictOptions&) -> core::Prediction {
    throw core::SolverError("balance LP (clp): numerical trouble");
  };
  PredictionLogic logic(PredictionConfig{}, failing);
  prediction_t p = logic.answer(one_block(-0.4));
  CHECK(p.status == prediction_t::STATUS_SOLVER_ERROR);
  CHECK(p.error == "balance LP (clp): numerical trouble");
  CHECK(p.num_blocks == 0);
  auto odd = [](const core::Stack&, const core::PredictOptions&) -> core::Prediction { throw std::bad_alloc(); };
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
}

TEST_CASE("measured positions get the default allowance, recorded in every answer") {
  PredictionLogic measured(PredictionConfig{});
  PredictionConfig exact_config;
  exact_config.position_tolerance = 0.0;
  PredictionLogic exact(exact_config);
  // A single block's knife edge is its centre over the surface edge (x = -0.5).
  const double t = kMeasuredPositionTolerance;
  for (double past : {0.2 * t, 0.9 * t}) {
    INFO("centre " << past << " past the edge");
    CHECK(measured.answer(one_block(-0.5 + past)).balanced);
    CHECK_FALSE(exact.answer(one_block(-0.5 + past)).balanced);
  }
  const prediction_t over = measured.answer(one_block(-0.5 + 1.5 * t));
  CHECK_FALSE(over.balanced);
  CHECK(over.blocks.at(0).state == block_prediction_t::STATE_CAUSE);
  CHECK(over.position_tolerance == t);
  CHECK(exact.answer(one_block(-0.6)).position_tolerance == 0.0);
  bricklayer::stack_t none = one_block(-0.6);
  none.status = bricklayer::stack_t::STATUS_NO_FRAME;
  CHECK(measured.answer(none).position_tolerance == t);  // failures say the configuration too
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
