// The measured-position allowance (PredictOptions::position_tolerance, modules/core/README.md "Tolerance
// policy"): contact intervals widened by t at both ends. Tested on both sides of the widened knife edge.
#include <catch2/catch.hpp>

#include <random>

#include "bricklayer/core/predict.h"
#include "bricklayer/piles/chaotic_pile.h"
#include "bricklayer/piles/known.h"
#include "bricklayer/piles/player_pile.h"

using namespace bricklayer::core;
using namespace bricklayer::piles;

namespace {

constexpr double kT = 0.005;  // bricklayer-prediction's default for measured stacks

bool balanced(const Stack& s, Annotator a, double tolerance) {
  PredictOptions o;
  o.annotator = a;
  o.position_tolerance = tolerance;
  const Prediction p = predict(s, o);
  CHECK(p.balanced == p.causes().empty());
  CHECK(p.position_tolerance == tolerance);
  return p.balanced;
}

Stack shifted(Stack s, double dx) {
  for (Block& b : s.blocks) b.x += dx;
  return s;
}

// Every block moved by a seeded uniform amount in [-amount, amount].
Stack jittered(Stack s, double amount, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> d(-amount, amount);
  for (Block& b : s.blocks) b.x += d(rng);
  return s;
}

std::vector<Stack> zero_margin_stacks() {
  std::vector<Stack> out = fixture_stacks();
  for (int n : {2, 3, 5, 10, 20, 40}) out.push_back(harmonic_stack(n));
  return out;
}

const Annotator kAll[] = {Annotator::kExact, Annotator::kPaper, Annotator::kBalance};

}  // namespace

TEST_CASE("a zero-margin pile shifted past the surface edge: balanced up to t, unbalanced beyond") {
  // The centre of mass of every optimum and harmonic stack is exactly over the edge, so the whole-pile
  // shift at which it tips is exactly the widening of the surface contact.
  for (const Stack& s : zero_margin_stacks()) {
    for (Annotator a : kAll) {
      INFO(s.blocks.size() << " blocks, " << to_string(a));
      CHECK_FALSE(balanced(shifted(s, 0.5 * kT), a, 0.0));  // exact positions: over the edge is over
      CHECK(balanced(shifted(s, 0.9 * kT), a, kT));
      CHECK_FALSE(balanced(shifted(s, 1.1 * kT), a, kT));
    }
  }
}

TEST_CASE("the rightmost block pushed out: within t balanced, 4 t out unbalanced and the cause") {
  for (const Stack& s : zero_margin_stacks()) {
    for (Annotator a : kAll) {
      INFO(s.blocks.size() << " blocks, " << to_string(a));
      CHECK_FALSE(balanced(push_rightmost(s, 0.5 * kT), a, 0.0));
      CHECK(balanced(push_rightmost(s, 0.9 * kT), a, kT));
      CHECK_FALSE(balanced(push_rightmost(s, 4 * kT), a, kT));
    }
    PredictOptions o;
    o.position_tolerance = kT;
    const Prediction p = predict(push_rightmost(s, 4 * kT), o);
    size_t rightmost = 0;
    for (size_t i = 1; i < s.blocks.size(); ++i)
      if (s.blocks[i].x > s.blocks[rightmost].x) rightmost = i;
    CHECK(p.blocks[rightmost].state != BlockState::kStable);
  }
}

TEST_CASE("measurement noise well inside t never turns a zero-margin pile red, without t it does") {
  int red_without = 0, trials = 0;
  for (const Stack& s : zero_margin_stacks()) {
    for (uint64_t seed = 1; seed <= 20; ++seed) {
      const Stack noisy = jittered(s, 0.25 * kT, seed);
      try {
        validate(noisy);
      } catch (const StackError&) {
        continue;  // blocks that touch in a row (the 3-block optimum) may now overlap: not a pile
      }
      INFO(s.blocks.size() << " blocks, seed " << seed);
      CHECK(balanced(noisy, Annotator::kExact, kT));
      red_without += !balanced(noisy, Annotator::kExact, 0.0);
      ++trials;
    }
  }
  INFO(red_without << " of " << trials << " noisy piles read unbalanced with exact positions");
  CHECK(red_without > trials / 4);  // the allowance is what keeps them blue
}

TEST_CASE("piles with a clear margin either way get the same verdict and causes with and without t") {
  // Player-like piles: where no block is within a few t of a knife edge, t changes nothing.
  int compared = 0, unbalanced = 0;
  for (uint64_t seed = 1; seed <= 400; ++seed) {
    const int n = 8 + static_cast<int>(seed % 40);
    const Stack s = seed % 2 ? player_pile(n, seed) : chaotic_pile(n, seed);
    PredictOptions exact, lenient, far;
    lenient.position_tolerance = kT;
    far.position_tolerance = 4 * kT;  // the verdict must not hinge on the widening
    const Prediction p0 = predict(s, exact), p1 = predict(s, lenient), p4 = predict(s, far);
    if (p0.balanced != p4.balanced || p0.causes() != p4.causes()) continue;  // near a knife edge: skip
    ++compared;
    unbalanced += !p0.balanced;
    INFO("seed " << seed);
    CHECK(p1.balanced == p0.balanced);
    CHECK(p1.causes() == p0.causes());
  }
  INFO(compared << " piles compared, " << unbalanced << " unbalanced");
  CHECK(compared >= 300);
  CHECK(unbalanced >= 100);
}

TEST_CASE("a position tolerance outside [0, kMaxPositionTolerance] is refused") {
  PredictOptions o;
  for (double bad : {-1e-3, kMaxPositionTolerance * 1.01, std::nan("")}) {
    o.position_tolerance = bad;
    CHECK_THROWS_AS(predict(harmonic_stack(3), o), std::invalid_argument);
  }
  o.position_tolerance = kMaxPositionTolerance;
  CHECK(predict(harmonic_stack(3), o).balanced);
}
