// NLopt backend: SLSQP, the only NLopt algorithm accurate enough here (NOTES.md). SLSQP reports success on
// infeasible problems, so this adapter checks the residuals itself and reports kInfeasible when they are
// above the feasibility tolerance.
#include <algorithm>
#include <cmath>

#include <nlopt.hpp>

#include "bricklayer/core/program.h"

namespace bricklayer::core::opt {
namespace {

struct Sparse {
  struct Term {
    int col;
    double value;
  };
  std::vector<std::vector<Term>> rows;
};

struct Context {
  const Problem* problem = nullptr;
  double scale = 1.0;  // the objective is multiplied by this (SLSQP behaves best with O(1) gradients)
  Sparse q;  // by first variable
  // Inequalities g(x) <= 0 and equalities h(x) = 0, each a sparse row of A (sign, offset).
  struct Row {
    int row;
    double sign;
    double offset;
  };
  std::vector<Row> inequalities, equalities;
  Sparse a;
};

double objective(unsigned n, const double* x, double* grad, void* data) {
  const auto* ctx = static_cast<const Context*>(data);
  double value = 0.0;
  for (unsigned i = 0; i < n; ++i) {
    value += ctx->problem->cost[i] * x[i];
    if (grad) grad[i] = ctx->problem->cost[i];
  }
  for (unsigned i = 0; i < n; ++i) {
    for (const auto& t : ctx->q.rows[i]) {
      value += 0.5 * t.value * x[i] * x[t.col];
      if (grad) grad[i] += t.value * x[t.col];  // Q symmetric
    }
  }
  if (grad) {
    for (unsigned i = 0; i < n; ++i) grad[i] *= ctx->scale;
  }
  return value * ctx->scale;
}

void constraints(const std::vector<Context::Row>& which, const Context& ctx, unsigned m, double* result, unsigned n,
                 const double* x, double* grad) {
  if (grad) std::fill(grad, grad + static_cast<size_t>(m) * n, 0.0);
  for (unsigned k = 0; k < m; ++k) {
    const auto& r = which[k];
    double value = 0.0;
    for (const auto& t : ctx.a.rows[static_cast<size_t>(r.row)]) {
      value += t.value * x[t.col];
      if (grad) grad[static_cast<size_t>(k) * n + static_cast<size_t>(t.col)] += r.sign * t.value;
    }
    result[k] = r.sign * value + r.offset;
  }
}

void inequality(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  const auto* ctx = static_cast<const Context*>(data);
  constraints(ctx->inequalities, *ctx, m, result, n, x, grad);
}

void equality(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  const auto* ctx = static_cast<const Context*>(data);
  constraints(ctx->equalities, *ctx, m, result, n, x, grad);
}

class NloptSolver final : public Solver {
 public:
  std::string name() const override { return "nlopt"; }
  bool available() const override { return true; }
  bool supports_quadratic() const override { return true; }

 protected:
  SolveResult do_solve(const Problem& problem, const SolverOptions& options) const override {
    const int n = problem.num_variables();
    SolveResult result;
    if (n == 0) {
      result.status = problem.max_violation({}) <= options.feasibility_tolerance ? SolveStatus::kOptimal
                                                                                  : SolveStatus::kInfeasible;
      return result;
    }
    Context ctx;
    ctx.problem = &problem;
    double largest = 0.0;
    for (double c : problem.cost) largest = std::max(largest, std::abs(c));
    for (const Entry& e : problem.q) largest = std::max(largest, std::abs(e.value));
    ctx.scale = largest > 0.0 ? 1.0 / largest : 1.0;
    ctx.q.rows.resize(static_cast<size_t>(n));
    for (const Entry& e : problem.q) ctx.q.rows[static_cast<size_t>(e.row)].push_back({e.col, e.value});
    ctx.a.rows.resize(static_cast<size_t>(problem.num_rows()));
    for (const Entry& e : problem.a) ctx.a.rows[static_cast<size_t>(e.row)].push_back({e.col, e.value});
    for (int r = 0; r < problem.num_rows(); ++r) {
      const double lo = problem.row_lower[r];
      const double hi = problem.row_upper[r];
      if (lo == hi) {
        ctx.equalities.push_back({r, 1.0, -lo});
        continue;
      }
      if (std::isfinite(hi)) ctx.inequalities.push_back({r, 1.0, -hi});   // a x - hi <= 0
      if (std::isfinite(lo)) ctx.inequalities.push_back({r, -1.0, lo});   // lo - a x <= 0
    }
    nlopt::opt opt(nlopt::LD_SLSQP, static_cast<unsigned>(n));
    opt.set_lower_bounds(std::vector<double>(problem.lower.begin(), problem.lower.end()));
    opt.set_upper_bounds(std::vector<double>(problem.upper.begin(), problem.upper.end()));
    opt.set_min_objective(objective, &ctx);
    if (!ctx.inequalities.empty()) {
      opt.add_inequality_mconstraint(inequality, &ctx, std::vector<double>(ctx.inequalities.size(), 1e-12));
    }
    if (!ctx.equalities.empty()) {
      opt.add_equality_mconstraint(equality, &ctx, std::vector<double>(ctx.equalities.size(), 1e-12));
    }
    opt.set_ftol_rel(1e-14);
    opt.set_xtol_rel(1e-12);
    opt.set_maxeval(options.max_iterations > 0 ? options.max_iterations : 100 + 20 * n);

    std::vector<double> x(static_cast<size_t>(n), 0.0);
    for (int i = 0; i < n; ++i) x[i] = std::clamp(0.0, problem.lower[i], problem.upper[i]);
    double value = 0.0;
    nlopt::result code = nlopt::FAILURE;
    bool roundoff = false;
    try {
      code = opt.optimize(x, value);
    } catch (const nlopt::roundoff_limited&) {
      roundoff = true;  // x holds the last iterate; judged by its residual below
      code = nlopt::ROUNDOFF_LIMITED;
    } catch (const nlopt::forced_stop&) {
      code = nlopt::FORCED_STOP;
    } catch (const std::bad_alloc&) {
      code = nlopt::OUT_OF_MEMORY;
    } catch (const std::invalid_argument&) {
      code = nlopt::INVALID_ARGS;
    } catch (const std::runtime_error&) {
      code = nlopt::FAILURE;
    }
    result.native_status = static_cast<int>(code);
    const double violation = problem.max_violation(x);
    const bool feasible = violation <= options.feasibility_tolerance;
    switch (code) {
      case nlopt::SUCCESS:
      case nlopt::STOPVAL_REACHED:
      case nlopt::FTOL_REACHED:
      case nlopt::XTOL_REACHED:
      case nlopt::ROUNDOFF_LIMITED:
        if (feasible) {
          result.status = SolveStatus::kOptimal;
        } else {
          result.status = SolveStatus::kInfeasible;
          result.message = "nlopt: SLSQP ended (code " + std::to_string(static_cast<int>(code)) +
                           ") with constraint violation " + std::to_string(violation);
        }
        break;
      case nlopt::MAXEVAL_REACHED:
      case nlopt::MAXTIME_REACHED:
        result.status = SolveStatus::kLimitReached;
        result.message = "nlopt: evaluation limit reached";
        break;
      default:
        result.status = SolveStatus::kError;
        result.message = "nlopt: SLSQP failed with code " + std::to_string(static_cast<int>(code));
        break;
    }
    (void)roundoff;
    if (result.status == SolveStatus::kOptimal) {
      result.x = x;
      result.objective = problem.objective(x);
      if (!std::isfinite(result.objective) || result.objective < -1e12) {
        result.status = SolveStatus::kUnbounded;
        result.message = "nlopt: objective diverges";
      }
    }
    return result;
  }
};

}  // namespace

std::unique_ptr<Solver> make_nlopt_solver() { return std::make_unique<NloptSolver>(); }

}  // namespace bricklayer::core::opt
