// One shared set of problems with known answers, run against every backend (STYLE.md items 1 and 2).
#include "bricklayer/core/program.h"

#include <catch2/catch.hpp>

using namespace bricklayer::core::opt;

namespace {

struct Known {
  const char* name;
  Problem problem;
  SolveStatus status;
  std::vector<double> x;  // expected solution when optimal
  double objective = 0.0;
};

Problem lp(std::vector<double> cost, std::vector<double> lower, std::vector<double> upper) {
  Problem p;
  for (size_t i = 0; i < cost.size(); ++i) p.add_variable(lower[i], upper[i], cost[i]);
  return p;
}

std::vector<Known> linear_programs() {
  std::vector<Known> out;
  {  // textbook corner: max x + y s.t. x + 2y <= 4, 3x + y <= 6
    Problem p = lp({-1, -1}, {0, 0}, {kInfinity, kInfinity});
    int r = p.add_row(-kInfinity, 4);
    p.set(r, 0, 1), p.set(r, 1, 2);
    r = p.add_row(-kInfinity, 6);
    p.set(r, 0, 3), p.set(r, 1, 1);
    out.push_back({"corner", p, SolveStatus::kOptimal, {1.6, 1.2}, -2.8});
  }
  {  // equality row
    Problem p = lp({1, 1}, {0, 0}, {10, 10});
    const int r = p.add_row(1, 1);
    p.set(r, 0, 1), p.set(r, 1, -1);
    out.push_back({"equality", p, SolveStatus::kOptimal, {1, 0}, 1});
  }
  {  // ranged row and a variable upper bound
    Problem p = lp({1, 0}, {0, 0}, {kInfinity, 1});
    const int r = p.add_row(2, 3);
    p.set(r, 0, 1), p.set(r, 1, 1);
    out.push_back({"range", p, SolveStatus::kOptimal, {1, 1}, 1});
  }
  {  // bounds only, negative lower bound, duplicate entries summed
    Problem p = lp({-1, 2}, {-3, -2}, {5, 4});
    const int r = p.add_row(-kInfinity, 100);
    p.set(r, 0, 0.5), p.set(r, 0, 0.5);
    out.push_back({"bounds", p, SolveStatus::kOptimal, {5, -2}, -9});
  }
  {  // force balance of a plank on two supports: f1 + f2 = 1, moments f1 * (-0.5) + f2 * 0.25 = 0
    Problem p = lp({0, 0}, {0, 0}, {kInfinity, kInfinity});
    int r = p.add_row(1, 1);
    p.set(r, 0, 1), p.set(r, 1, 1);
    r = p.add_row(0, 0);
    p.set(r, 0, -0.5), p.set(r, 1, 0.25);
    out.push_back({"plank", p, SolveStatus::kOptimal, {1.0 / 3.0, 2.0 / 3.0}, 0});
  }
  {  // infeasible: x + y <= 1 and x + y >= 2
    Problem p = lp({1, 1}, {0, 0}, {kInfinity, kInfinity});
    int r = p.add_row(-kInfinity, 1);
    p.set(r, 0, 1), p.set(r, 1, 1);
    r = p.add_row(2, kInfinity);
    p.set(r, 0, 1), p.set(r, 1, 1);
    out.push_back({"infeasible", p, SolveStatus::kInfeasible, {}, 0});
  }
  return out;
}

}  // namespace

TEST_CASE("every backend solves the shared linear programs with known answers") {
  const std::string backend = GENERATE(from_range(solver_names()));
  const auto solver = make_solver(backend);
  REQUIRE(solver->available());
  // Per-backend tolerance: CLP is a simplex code (exact vertices); SLSQP is iterative.
  const double tol = backend == "clp" ? 1e-9 : 1e-6;
  for (const Known& k : linear_programs()) {
    INFO(backend << ": " << k.name);
    const SolveResult r = solver->solve(k.problem);
    CHECK(r.solver == backend);
    REQUIRE(r.status == k.status);
    if (k.status != SolveStatus::kOptimal) {
      CHECK_FALSE(r.message.empty());
      continue;
    }
    REQUIRE(r.x.size() == k.x.size());
    for (size_t i = 0; i < k.x.size(); ++i) CHECK(r.x[i] == Approx(k.x[i]).margin(tol));
    CHECK(r.objective == Approx(k.objective).margin(tol));
    CHECK(k.problem.max_violation(r.x) <= tol);
  }
}

TEST_CASE("an unbounded LP is never reported optimal") {
  const std::string backend = GENERATE(from_range(solver_names()));
  Problem p = lp({-1, 0}, {0, 0}, {kInfinity, kInfinity});
  const int r = p.add_row(-kInfinity, 1);
  p.set(r, 0, 1), p.set(r, 1, -1);
  const SolveResult result = make_solver(backend)->solve(p);
  INFO(backend << ": " << to_string(result.status) << " " << result.message);
  if (backend == "clp") {
    CHECK(result.status == SolveStatus::kUnbounded);
  } else {
    CHECK(result.status != SolveStatus::kOptimal);
  }
}

TEST_CASE("convex QP: NLopt solves it, CLP says it does not take quadratic objectives") {
  // minimise 1/2 (x - 1)^2 + 1/2 (y - 2)^2 s.t. x + y <= 1  ->  (0, 1)
  Problem p;
  p.add_variable(-kInfinity, kInfinity, -1);
  p.add_variable(-kInfinity, kInfinity, -2);
  p.add_quadratic(0, 0, 1);
  p.add_quadratic(1, 1, 1);
  const int r = p.add_row(-kInfinity, 1);
  p.set(r, 0, 1), p.set(r, 1, 1);
  const SolveResult nlopt = make_solver("nlopt")->solve(p);
  REQUIRE(nlopt.status == SolveStatus::kOptimal);
  CHECK(nlopt.x[0] == Approx(0).margin(1e-7));
  CHECK(nlopt.x[1] == Approx(1).margin(1e-7));
  const SolveResult clp = make_solver("clp")->solve(p);
  CHECK(clp.status == SolveStatus::kError);
  CHECK(clp.message.find("quadratic") != std::string::npos);
}

TEST_CASE("malformed problems and unknown backends are errors, not crashes") {
  Problem p = lp({1}, {2}, {1});  // lower > upper
  for (const auto& name : solver_names()) {
    const SolveResult r = make_solver(name)->solve(p);
    CHECK(r.status == SolveStatus::kError);
    CHECK(r.message.find("malformed") != std::string::npos);
  }
  Problem q = lp({1}, {0}, {1});
  q.set(0, 0, 1.0);  // row 0 does not exist
  CHECK(make_solver("clp")->solve(q).status == SolveStatus::kError);
  CHECK_THROWS_AS(make_solver("gurobi"), std::invalid_argument);
  CHECK(to_string(SolveStatus::kLimitReached) == "limit_reached");
}

TEST_CASE("an iteration limit is reported as limit_reached") {
  // A 30-variable LP that needs more than one simplex pivot / SLSQP evaluation.
  Problem p;
  for (int i = 0; i < 30; ++i) p.add_variable(0, kInfinity, -1.0 - i);
  for (int i = 0; i < 30; ++i) {
    const int r = p.add_row(-kInfinity, 1.0 + i);
    for (int j = 0; j <= i; ++j) p.set(r, j, 1.0);
  }
  SolverOptions options;
  options.max_iterations = 1;
  for (const auto& name : solver_names()) {
    INFO(name);
    CHECK(make_solver(name)->solve(p, options).status == SolveStatus::kLimitReached);
  }
}

TEST_CASE("a basis hint (good, singular or wrong-sized) never changes the answer") {
  for (const auto& name : solver_names()) {
    for (const Known& k : linear_programs()) {
      if (k.status != SolveStatus::kOptimal) continue;
      const double tol = name == "clp" ? 1e-9 : 1e-6;
      for (int variant = 0; variant < 3; ++variant) {
        Problem p = k.problem;
        if (variant == 0) {  // one variable per row, in order
          for (int r = 0; r < p.num_rows(); ++r) p.basis_hint.push_back(r % p.num_variables());
        } else if (variant == 1) {  // all the same variable: singular
          p.basis_hint.assign(static_cast<size_t>(p.num_rows()), 0);
        } else {  // wrong size: ignored
          p.basis_hint = {0, 0, 0, 0, 0};
        }
        INFO(name << ": " << k.name << " variant " << variant);
        const SolveResult r = make_solver(name)->solve(p);
        REQUIRE(r.status == SolveStatus::kOptimal);
        CHECK(r.objective == Approx(k.objective).margin(tol));
      }
    }
  }
  Problem bad = linear_programs()[0].problem;
  bad.basis_hint = {0, 7};
  CHECK(make_solver("clp")->solve(bad).status == SolveStatus::kError);
}

TEST_CASE("clp: a warm start from the final basis re-solves without pivots, a changed problem from there gets the cold answer") {
  const auto clp = make_solver("clp");
  for (const Known& k : linear_programs()) {
    if (k.status != SolveStatus::kOptimal) continue;
    INFO(k.name);
    Problem p = k.problem;
    const SolveResult cold = clp->solve(p);
    REQUIRE(cold.status == SolveStatus::kOptimal);
    REQUIRE(cold.basis.variables.size() == static_cast<size_t>(p.num_variables()));
    REQUIRE(cold.basis.rows.size() == static_cast<size_t>(p.num_rows()));
    p.warm_start = cold.basis;
    const SolveResult again = clp->solve(p);
    REQUIRE(again.status == SolveStatus::kOptimal);
    CHECK(again.iterations == 0);
    for (size_t i = 0; i < cold.x.size(); ++i) CHECK(again.x[i] == Approx(cold.x[i]).margin(1e-12));
  }
  // The textbook corner with its second row loosened (6 -> 8): from the old basis, the new optimum.
  Problem p = linear_programs()[0].problem;
  const SolveResult first = clp->solve(p);
  p.row_upper[1] = 8.0;
  const SolveResult cold = clp->solve(p);
  p.warm_start = first.basis;
  const SolveResult warm = clp->solve(p);
  REQUIRE(cold.status == SolveStatus::kOptimal);
  REQUIRE(warm.status == SolveStatus::kOptimal);
  CHECK(warm.objective == Approx(cold.objective).margin(1e-12));
  CHECK(warm.x[0] == Approx(2.4).margin(1e-12));  // x + 2y = 4, 3x + y = 8
  CHECK(warm.x[1] == Approx(0.8).margin(1e-12));
  CHECK(warm.iterations <= cold.iterations);
}

TEST_CASE("a warm-start basis of the wrong shape is a malformed problem, a backend without bases ignores one") {
  Problem p = linear_programs()[0].problem;
  p.warm_start.variables = {BasisStatus::kBasic};
  p.warm_start.rows = {BasisStatus::kBasic, BasisStatus::kBasic};
  for (const auto& name : solver_names()) {
    const SolveResult r = make_solver(name)->solve(p);
    CHECK(r.status == SolveStatus::kError);
    CHECK(r.message.find("warm-start basis") != std::string::npos);
  }
  p.warm_start.variables = {BasisStatus::kBasic, BasisStatus::kAtLower};
  const SolveResult nlopt = make_solver("nlopt")->solve(p);
  REQUIRE(nlopt.status == SolveStatus::kOptimal);
  CHECK(nlopt.objective == Approx(-2.8).margin(1e-6));
  CHECK(nlopt.basis.empty());
}

TEST_CASE("clp without scaling gives the same answers on the shared problems") {
  SolverOptions options;
  options.scale = false;
  for (const Known& k : linear_programs()) {
    INFO(k.name);
    const SolveResult r = make_solver("clp")->solve(k.problem, options);
    REQUIRE(r.status == k.status);
    if (k.status != SolveStatus::kOptimal) continue;
    for (size_t i = 0; i < k.x.size(); ++i) CHECK(r.x[i] == Approx(k.x[i]).margin(1e-9));
  }
}
