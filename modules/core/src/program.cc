#include "bricklayer/core/program.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace bricklayer::core::opt {

std::string to_string(SolveStatus status) {
  switch (status) {
    case SolveStatus::kOptimal: return "optimal";
    case SolveStatus::kInfeasible: return "infeasible";
    case SolveStatus::kUnbounded: return "unbounded";
    case SolveStatus::kLimitReached: return "limit_reached";
    case SolveStatus::kError: return "error";
  }
  return "error";
}

int Problem::add_variable(double lo, double hi, double c) {
  lower.push_back(lo);
  upper.push_back(hi);
  cost.push_back(c);
  return num_variables() - 1;
}

int Problem::add_row(double lo, double hi) {
  row_lower.push_back(lo);
  row_upper.push_back(hi);
  return num_rows() - 1;
}

std::string Problem::check() const {
  std::ostringstream out;
  const int n = num_variables();
  if (lower.size() != cost.size() || upper.size() != cost.size()) return "lower/upper/cost sizes differ";
  if (row_lower.size() != row_upper.size()) return "row_lower/row_upper sizes differ";
  for (int i = 0; i < n; ++i) {
    if (std::isnan(lower[i]) || std::isnan(upper[i]) || !std::isfinite(cost[i])) {
      out << "variable " << i << ": NaN bound or non-finite cost";
      return out.str();
    }
    if (lower[i] > upper[i]) {
      out << "variable " << i << ": lower bound " << lower[i] << " > upper bound " << upper[i];
      return out.str();
    }
  }
  for (int r = 0; r < num_rows(); ++r) {
    if (std::isnan(row_lower[r]) || std::isnan(row_upper[r]) || row_lower[r] > row_upper[r]) {
      out << "row " << r << ": bounds [" << row_lower[r] << ", " << row_upper[r] << "] are not an interval";
      return out.str();
    }
  }
  for (const Entry& e : a) {
    if (e.row < 0 || e.row >= num_rows() || e.col < 0 || e.col >= n || !std::isfinite(e.value)) {
      out << "constraint entry (" << e.row << ", " << e.col << ") out of range or not finite";
      return out.str();
    }
  }
  if (!warm_start.empty() && (static_cast<int>(warm_start.variables.size()) != n ||
                              static_cast<int>(warm_start.rows.size()) != num_rows())) {
    out << "warm-start basis has " << warm_start.variables.size() << " variables and " << warm_start.rows.size()
        << " rows, the problem " << n << " and " << num_rows();
    return out.str();
  }
  for (int v : basis_hint) {
    if (v < 0 || v >= n) {
      out << "basis hint variable " << v << " out of range";
      return out.str();
    }
  }
  for (const Entry& e : q) {
    if (e.row < 0 || e.row >= n || e.col < 0 || e.col >= n || !std::isfinite(e.value)) {
      out << "quadratic entry (" << e.row << ", " << e.col << ") out of range or not finite";
      return out.str();
    }
  }
  return {};
}

double Problem::max_violation(const std::vector<double>& x) const {
  double worst = 0.0;
  for (int i = 0; i < num_variables(); ++i) {
    worst = std::max(worst, lower[i] - x[i]);
    worst = std::max(worst, x[i] - upper[i]);
  }
  std::vector<double> ax(static_cast<size_t>(num_rows()), 0.0);
  for (const Entry& e : a) ax[e.row] += e.value * x[e.col];
  for (int r = 0; r < num_rows(); ++r) {
    worst = std::max(worst, row_lower[r] - ax[r]);
    worst = std::max(worst, ax[r] - row_upper[r]);
  }
  return worst;
}

double Problem::objective(const std::vector<double>& x) const {
  double value = 0.0;
  for (int i = 0; i < num_variables(); ++i) value += cost[i] * x[i];
  for (const Entry& e : q) value += 0.5 * e.value * x[e.row] * x[e.col];
  return value;
}

SolveResult Solver::solve(const Problem& problem, const SolverOptions& options) const {
  SolveResult result;
  result.solver = name();
  if (!available()) {
    result.message = name() + ": not compiled in (configure with -DBRICKLAYER_WITH_" +
                     (name() == "clp" ? std::string("CLP") : std::string("NLOPT")) + "=ON)";
    return result;
  }
  if (std::string problem_error = problem.check(); !problem_error.empty()) {
    result.message = name() + ": malformed problem: " + problem_error;
    return result;
  }
  if (!problem.is_linear() && !supports_quadratic()) {
    result.message = name() + ": quadratic objectives are not supported by this backend";
    return result;
  }
  try {
    result = do_solve(problem, options);
  } catch (const std::exception& e) {
    result = SolveResult{};
    result.message = name() + ": " + e.what();
  }
  result.solver = name();
  return result;
}

std::vector<std::string> solver_names() { return {"clp", "nlopt"}; }

std::unique_ptr<Solver> make_clp_solver();    // clp_solver.cc or no_clp.cc
std::unique_ptr<Solver> make_nlopt_solver();  // nlopt_solver.cc or no_nlopt.cc

std::unique_ptr<Solver> make_solver(const std::string& name) {
  if (name == "clp") return make_clp_solver();
  if (name == "nlopt") return make_nlopt_solver();
  throw std::invalid_argument("unknown solver \"" + name + "\" (expected clp or nlopt)");
}

}  // namespace bricklayer::core::opt
