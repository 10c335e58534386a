// COIN-OR CLP backend: linear programs only (CLP's quadratic solver is unreliable on these problems).
#include <cmath>

#include <ClpSimplex.hpp>

#include "bricklayer/core/program.h"

namespace bricklayer::core::opt {
namespace {

double to_clp(double bound) {
  if (bound == kInfinity) return COIN_DBL_MAX;
  if (bound == -kInfinity) return -COIN_DBL_MAX;
  return bound;
}

ClpSimplex::Status to_clp(BasisStatus status) {
  switch (status) {
    case BasisStatus::kBasic: return ClpSimplex::basic;
    case BasisStatus::kAtLower: return ClpSimplex::atLowerBound;
    case BasisStatus::kAtUpper: return ClpSimplex::atUpperBound;
    case BasisStatus::kFree: return ClpSimplex::isFree;
    case BasisStatus::kSuperbasic: return ClpSimplex::superBasic;
    case BasisStatus::kFixed: return ClpSimplex::isFixed;
  }
  return ClpSimplex::superBasic;
}

BasisStatus from_clp(ClpSimplex::Status status) {
  switch (status) {
    case ClpSimplex::basic: return BasisStatus::kBasic;
    case ClpSimplex::atLowerBound: return BasisStatus::kAtLower;
    case ClpSimplex::atUpperBound: return BasisStatus::kAtUpper;
    case ClpSimplex::isFree: return BasisStatus::kFree;
    case ClpSimplex::superBasic: return BasisStatus::kSuperbasic;
    case ClpSimplex::isFixed: return BasisStatus::kFixed;
  }
  return BasisStatus::kSuperbasic;
}

class ClpSolver final : public Solver {
 public:
  std::string name() const override { return "clp"; }
  bool available() const override { return true; }
  bool supports_quadratic() const override { return false; }

 protected:
  SolveResult do_solve(const Problem& problem, const SolverOptions& options) const override {
    const int n = problem.num_variables();
    const int m = problem.num_rows();
    // Column-ordered (CSC) arrays by counting sort; duplicates are kept (CLP sums them).
    std::vector<CoinBigIndex> starts(static_cast<size_t>(n) + 1, 0);
    for (const Entry& e : problem.a) ++starts[static_cast<size_t>(e.col) + 1];
    for (int j = 0; j < n; ++j) starts[static_cast<size_t>(j) + 1] += starts[static_cast<size_t>(j)];
    std::vector<int> rows(problem.a.size());
    std::vector<double> values(problem.a.size());
    {
      std::vector<CoinBigIndex> next(starts.begin(), starts.end() - 1);
      for (const Entry& e : problem.a) {
        const CoinBigIndex at = next[static_cast<size_t>(e.col)]++;
        rows[static_cast<size_t>(at)] = e.row;
        values[static_cast<size_t>(at)] = e.value;
      }
    }
    std::vector<double> lo(n), hi(n), rlo(m), rhi(m);
    for (int i = 0; i < n; ++i) lo[i] = to_clp(problem.lower[i]), hi[i] = to_clp(problem.upper[i]);
    for (int r = 0; r < m; ++r) rlo[r] = to_clp(problem.row_lower[r]), rhi[r] = to_clp(problem.row_upper[r]);

    ClpSimplex model;
    model.setLogLevel(0);
    if (!options.scale) model.scaling(0);
    model.loadProblem(n, m, starts.data(), rows.data(), values.data(), lo.data(), hi.data(), problem.cost.data(),
                      rlo.data(), rhi.data());
    const bool warm = !problem.warm_start.empty();
    if (warm) {
      model.createStatus();
      for (int i = 0; i < n; ++i) model.setColumnStatus(i, to_clp(problem.warm_start.variables[i]));
      for (int r = 0; r < m; ++r) model.setRowStatus(r, to_clp(problem.warm_start.rows[r]));
    } else if (static_cast<int>(problem.basis_hint.size()) == m && m > 0) {
      model.createStatus();
      for (int i = 0; i < n; ++i) {
        if (std::isfinite(problem.lower[i])) {
          model.setColumnStatus(i, ClpSimplex::atLowerBound);
        } else if (std::isfinite(problem.upper[i])) {
          model.setColumnStatus(i, ClpSimplex::atUpperBound);
        } else {
          model.setColumnStatus(i, ClpSimplex::isFree);
        }
      }
      for (int r = 0; r < m; ++r) model.setRowStatus(r, ClpSimplex::atLowerBound);
      for (int v : problem.basis_hint) model.setColumnStatus(v, ClpSimplex::basic);
    }
    model.setPrimalTolerance(options.feasibility_tolerance);
    model.setDualTolerance(options.optimality_tolerance);
    if (options.max_iterations > 0) model.setMaximumIterations(options.max_iterations);
    const bool hinted = !warm && static_cast<int>(problem.basis_hint.size()) == m && m > 0;
    if (hinted && problem.hint_primal_feasible) {
      model.primal();
    } else {
      model.dual();
    }

    SolveResult result;
    result.native_status = model.status();
    result.iterations = model.numberIterations();
    switch (model.status()) {
      case 0: result.status = SolveStatus::kOptimal; break;
      case 1: result.status = SolveStatus::kInfeasible; result.message = "clp: primal infeasible"; break;
      case 2: result.status = SolveStatus::kUnbounded; result.message = "clp: dual infeasible (unbounded)"; break;
      case 3: result.status = SolveStatus::kLimitReached; result.message = "clp: iteration or time limit"; break;
      default: result.status = SolveStatus::kError; result.message = "clp: stopped with status " + std::to_string(model.status()); break;
    }
    result.basis.variables.resize(static_cast<size_t>(n));
    result.basis.rows.resize(static_cast<size_t>(m));
    for (int i = 0; i < n; ++i) result.basis.variables[i] = from_clp(model.getColumnStatus(i));
    for (int r = 0; r < m; ++r) result.basis.rows[r] = from_clp(model.getRowStatus(r));
    if (result.status == SolveStatus::kOptimal) {
      const double* x = model.primalColumnSolution();
      result.x.assign(x, x + n);
      result.objective = model.objectiveValue();
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Solver> make_clp_solver() { return std::make_unique<ClpSolver>(); }

}  // namespace bricklayer::core::opt
