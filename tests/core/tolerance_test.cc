// The tolerance policy (modules/core/README.md), tested on both sides of the knife edge.
#include <catch2/catch.hpp>

#include "bricklayer/core/predict.h"
#include "bricklayer/piles/chaotic_pile.h"
#include "bricklayer/piles/known.h"
#include "bricklayer/piles/player_pile.h"

using namespace bricklayer::core;
using namespace bricklayer::piles;

namespace {

bool balanced(const Stack& s, Annotator a, const std::string& solver) {
  PredictOptions o;
  o.annotator = a;
  o.solver = solver;
  const Prediction p = predict(s, o);
  CHECK(p.balanced == p.causes().empty());
  return p.balanced;
}

const Annotator kAll[] = {Annotator::kExact, Annotator::kPaper, Annotator::kBalance};

}  // namespace

TEST_CASE("every fixture stack is balanced, pushing its rightmost block right by 1e-3 unbalances it") {
  for (const Stack& s : fixture_stacks()) {
    for (const char* solver : {"clp", "nlopt"}) {
      for (Annotator a : kAll) {
        INFO(s.blocks.size() << " blocks, " << to_string(a) << ", " << solver);
        CHECK(balanced(s, a, solver));
        CHECK(balanced(push_rightmost(s, 1e-8), a, solver));  // inside the tolerance
        CHECK_FALSE(balanced(push_rightmost(s, 1e-3), a, solver));
      }
    }
  }
}

TEST_CASE("harmonic stacks of 2..50 blocks: balanced, 1e-3 further out unbalanced, 1e-3 back balanced") {
  for (int n = 2; n <= 50; ++n) {
    const Stack s = harmonic_stack(n);
    for (Annotator a : kAll) {
      INFO(n << " blocks, " << to_string(a));
      CHECK(balanced(s, a, "clp"));
      CHECK(balanced(push_rightmost(s, 1e-8), a, "clp"));
      CHECK_FALSE(balanced(push_rightmost(s, 1e-3), a, "clp"));
      CHECK(balanced(push_rightmost(s, -1e-3), a, "clp"));
    }
    if (n <= 8) {
      for (Annotator a : kAll) {
        INFO(n << " blocks, " << to_string(a) << ", nlopt");
        CHECK(balanced(s, a, "nlopt"));
        CHECK_FALSE(balanced(push_rightmost(s, 1e-3), a, "nlopt"));
      }
    }
  }
}

TEST_CASE("the knife edge in the exact annotator: the pushed top block of a harmonic stack is the cause") {
  for (int n : {2, 10, 50, 400}) {  // 400: long Lawson-Hanson runs exercise the factor's band rebuilds
    const Prediction p = predict(push_rightmost(harmonic_stack(n), 1e-3));
    INFO(n);
    REQUIRE_FALSE(p.causes().empty());
    CHECK(p.blocks.back().state != BlockState::kStable);  // the top block moves
  }
}
