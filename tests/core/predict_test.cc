// The annotators on known cases, and the properties that tie them together.
#include "bricklayer/core/predict.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "bricklayer/core/contacts.h"
#include "bricklayer/core/dynamics.h"
#include "bricklayer/piles/chaotic_pile.h"
#include "bricklayer/piles/known.h"
#include "bricklayer/piles/player_pile.h"

using namespace bricklayer::core;
using namespace bricklayer::piles;
using Ids = std::vector<int64_t>;

namespace {

Prediction run(const Stack& s, Annotator annotator, const std::string& solver = "clp",
               QpMethod qp = QpMethod::kNnls, bool lp_first = true) {
  PredictOptions o;
  o.annotator = annotator;
  o.solver = solver;
  o.qp = qp;
  o.lp_first = lp_first;
  return predict(s, o);
}

}  // namespace

TEST_CASE("Figure 15: the upper block alone is unbalanced") {
  const Stack s = figure15_upper_alone();
  for (const char* solver : {"clp", "nlopt"}) {
    INFO(solver);
    const Prediction exact = run(s, Annotator::kExact, solver);
    CHECK_FALSE(exact.balanced);
    CHECK(exact.causes() == Ids{2});
    CHECK(exact.moving() == Ids{2});
    CHECK(run(s, Annotator::kPaper, solver).causes() == Ids{2});
    CHECK(run(s, Annotator::kBalance, solver).causes() == Ids{0, 1, 2});
  }
}

TEST_CASE("Figure 15: both the middle and the upper block are unbalanced") {
  const Stack s = figure15_both();
  for (const char* solver : {"clp", "nlopt"}) {
    INFO(solver);
    const Prediction exact = run(s, Annotator::kExact, solver);
    CHECK_FALSE(exact.balanced);
    CHECK(exact.causes() == Ids{1, 2});
    CHECK(exact.moving() == Ids{1, 2});
    CHECK(run(s, Annotator::kPaper, solver).causes() == Ids{1, 2});
  }
}

TEST_CASE("Figure 15: the middle block alone, only the middle block is red under the exact annotator") {
  const Stack s = figure15_middle_alone();
  const Prediction exact = run(s, Annotator::kExact);
  CHECK_FALSE(exact.balanced);
  CHECK(exact.causes() == Ids{1});
  CHECK(exact.moving() == Ids{1, 2});  // the upper block rides on the falling middle block
  CHECK(exact.blocks[2].state == BlockState::kMoving);
  CHECK(exact.blocks[0].state == BlockState::kStable);
  // The middle block tips clockwise about the bottom block's right end.
  CHECK(exact.blocks[1].alpha < -1e-3);
  CHECK(exact.blocks[0].accel == Approx(0.0).margin(1e-12));
  const Prediction paper = run(s, Annotator::kPaper);
  CHECK(paper.causes() == Ids{1});  // supporting the lower block directly is cheaper
}

TEST_CASE("a block resting on nothing is a cause, and so is whatever tips with it held") {
  Stack s = column({-0.5, -0.5});
  s.blocks.push_back({7, 3, -0.5});  // row 3 above an empty row 2: floats
  const Prediction exact = run(s, Annotator::kExact);
  CHECK_FALSE(exact.balanced);
  CHECK(exact.causes() == Ids{7});
  CHECK(exact.blocks[2].accel == Approx(-1.0));  // free fall, units of g
  CHECK(run(s, Annotator::kPaper).causes() == Ids{7});
  // A row-0 block entirely beyond the edge floats too.
  const Stack off = column({0.25});
  CHECK(run(off, Annotator::kExact).causes() == Ids{0});
  CHECK(run(off, Annotator::kPaper).causes() == Ids{0});
}

TEST_CASE("score and overhang, an empty pile is balanced") {
  Stack s = column({-0.5, -0.25});
  s.block_length = 2.0;  // units: x in the same unit as block_length
  s.table_edge = -1.0;
  s.blocks = {{0, 0, -2.0}, {1, 1, -1.0}};
  const Prediction p = run(s, Annotator::kExact);
  CHECK(p.overhang == Approx(1.0));  // right end at 1.0, edge -1.0, two units = one block length
  CHECK(p.score == 100);
  CHECK(score_of(1.30455) == 130);
  CHECK(score_of(0.005) == 1);
  const Prediction empty = run(Stack{}, Annotator::kExact);
  CHECK(empty.balanced);
  CHECK(empty.score == 0);
  const nlohmann::json j = to_json(p);
  for (const char* key : {"balanced", "unbalanced", "moving", "overhang", "score", "annotator", "solver", "blocks"}) {
    CHECK(j.contains(key));
  }
}

TEST_CASE("balanced by the LP == all initial accelerations zero, on a few hundred generated piles") {
  int unbalanced = 0;
  for (uint64_t seed = 0; seed < 300; ++seed) {
    const Stack s = seed % 2 ? chaotic_pile(4 + static_cast<int>(seed % 23), seed) : player_pile(5 + static_cast<int>(seed % 40), seed);
    const ContactGraph g = build_contacts(s);
    const bool lp_balanced = balance_violation(g, "clp") <= kBalanceTolerance;
    const Accelerations acc = initial_accelerations(g);
    INFO("seed " << seed);
    REQUIRE(acc.converged);
    CHECK(lp_balanced == !acc.any_moving());
    unbalanced += lp_balanced ? 0 : 1;
  }
  // Both verdicts occur often enough for the agreement to mean something.
  CHECK(unbalanced > 60);
  CHECK(unbalanced < 240);
}

TEST_CASE("exact causes are never empty for an unbalanced pile, and every cause moves when its lower rows are held") {
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const Stack s = chaotic_pile(3 + static_cast<int>(seed % 30), 1000 + seed);
    const Prediction p = run(s, Annotator::kExact, "clp", QpMethod::kNnls, seed % 2 == 0);
    INFO("seed " << seed);
    CHECK(p.balanced == p.causes().empty());
    CHECK(p.balanced == p.moving().empty());
    // Check the definition directly for each block: moving with rows below held fixed.
    const ContactGraph g = build_contacts(s);
    for (size_t i = 0; i < s.blocks.size(); ++i) {
      std::vector<char> free(s.blocks.size(), 0);
      for (size_t k = 0; k < s.blocks.size(); ++k) free[k] = s.blocks[k].row >= s.blocks[i].row;
      const bool cause = initial_accelerations(g, free).moving(i);
      INFO("block " << i);
      CHECK(cause == (p.blocks[i].state == BlockState::kCause));
    }
  }
}

TEST_CASE("the LP-first shortcut changes nothing") {
  for (uint64_t seed = 0; seed < 100; ++seed) {
    const Stack s = player_pile(10 + static_cast<int>(seed % 50), 500 + seed);
    const Prediction a = run(s, Annotator::kExact, "clp", QpMethod::kNnls, true);
    const Prediction b = run(s, Annotator::kExact, "clp", QpMethod::kNnls, false);
    CHECK(a.balanced == b.balanced);
    CHECK(a.causes() == b.causes());
    CHECK(a.moving() == b.moving());
  }
}

TEST_CASE("CLP and NLopt agree on a generated set of small stacks") {
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const Stack s = chaotic_pile(3 + static_cast<int>(seed % 6), 7000 + seed);
    INFO("seed " << seed);
    for (Annotator a : {Annotator::kBalance, Annotator::kExact, Annotator::kPaper}) {
      INFO(to_string(a));
      const Prediction clp = run(s, a, "clp");
      const Prediction nlopt = run(s, a, "nlopt");
      CHECK(clp.balanced == nlopt.balanced);
      CHECK(clp.causes() == nlopt.causes());
    }
  }
}

TEST_CASE("the NNLS dual and NLopt's primal QP give the same accelerations") {
  for (uint64_t seed = 0; seed < 40; ++seed) {
    const Stack s = chaotic_pile(3 + static_cast<int>(seed % 8), 9000 + seed);
    const ContactGraph g = build_contacts(s);
    const Accelerations nnls = initial_accelerations(g, {}, QpMethod::kNnls);
    const Accelerations slsqp = initial_accelerations(g, {}, QpMethod::kNlopt);
    INFO("seed " << seed);
    for (size_t i = 0; i < g.size(); ++i) {
      CHECK(nnls.a[i] == Approx(slsqp.a[i]).margin(1e-6));
      CHECK(nnls.alpha[i] == Approx(slsqp.alpha[i]).margin(1e-5));
      CHECK(nnls.moving(i) == slsqp.moving(i));
    }
    const Prediction a = run(s, Annotator::kExact, "clp", QpMethod::kNnls, false);
    const Prediction b = run(s, Annotator::kExact, "clp", QpMethod::kNlopt, false);
    CHECK(a.causes() == b.causes());
  }
}
