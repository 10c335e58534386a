// One optimisation problem, many solvers (Drake's MathematicalProgram + final adapters, made small).
//
//   minimise    c^T x + 1/2 x^T Q x
//   subject to  row_lower <= A x <= row_upper,   lower <= x <= upper
//
// A Problem is written once; Solver::solve() does every shared check (compiled in? problem well formed?
// quadratic objective supported?) and then calls one backend's protected hook. Every backend maps its
// native result codes onto the one SolveStatus vocabulary and keeps the native code on the side.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace bricklayer::core::opt {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

enum class SolveStatus { kOptimal, kInfeasible, kUnbounded, kLimitReached, kError };
std::string to_string(SolveStatus status);

// A simplex basis: where each variable and each row (its activity) stands. Backends without a basis (NLopt)
// ignore it and report none. Passing a solver's final basis back with a problem of the same shape (a
// sequence of related linear programs, as in sequential linear programming) lets it start from there.
enum class BasisStatus : uint8_t { kBasic, kAtLower, kAtUpper, kFree, kSuperbasic, kFixed };

struct Basis {
  std::vector<BasisStatus> variables;  // one per variable
  std::vector<BasisStatus> rows;       // one per row
  bool empty() const { return variables.empty() && rows.empty(); }
};

struct Entry {
  int row = 0;  // (for Q: first variable)
  int col = 0;
  double value = 0.0;
};

struct Problem {
  std::vector<double> lower, upper, cost;  // one per variable
  std::vector<double> row_lower, row_upper;  // one per linear constraint (equal bounds: an equality)
  std::vector<Entry> a;  // constraint matrix entries (duplicates are summed)
  std::vector<Entry> q;  // quadratic objective entries; give both (i,j) and (j,i) for off-diagonal terms
  // Optional warm start for simplex backends: one variable per row to make basic (the others start at a
  // bound). Ignored unless it has exactly num_rows() entries; a singular hint is repaired by the backend.
  std::vector<int> basis_hint;
  bool hint_primal_feasible = false;  // the hint's basic solution satisfies the bounds: start with primal simplex
  // Optional full starting basis (e.g. SolveResult::basis of the previous problem of a sequence); when
  // given it must have one status per variable and per row, and it replaces basis_hint. A basis that does
  // not fit the new bounds is repaired by the backend (CLP's dual simplex starts from it).
  Basis warm_start;

  int num_variables() const { return static_cast<int>(cost.size()); }
  int num_rows() const { return static_cast<int>(row_lower.size()); }
  bool is_linear() const { return q.empty(); }

  int add_variable(double lo, double hi, double c);
  int add_row(double lo, double hi);
  void set(int row, int var, double value) { a.push_back({row, var, value}); }
  void add_quadratic(int i, int j, double value) { q.push_back({i, j, value}); }

  // Empty when well formed, else a one-line description of the first problem found.
  std::string check() const;
  // Largest violation of the rows and bounds at x (absolute).
  double max_violation(const std::vector<double>& x) const;
  double objective(const std::vector<double>& x) const;
};

struct SolveResult {
  SolveStatus status = SolveStatus::kError;
  std::vector<double> x;      // the solution when status == kOptimal
  double objective = 0.0;
  std::string message;        // human-readable detail (always set unless optimal)
  int native_status = 0;      // the backend's own code, for diagnostics only
  std::string solver;         // which backend answered
  Basis basis;                // simplex backends: the final basis (also when not optimal), for a warm start
  int iterations = 0;         // simplex pivots (CLP); 0 where the backend does not count them
};

struct SolverOptions {
  double feasibility_tolerance = 1e-9;  // accepted violation of rows and bounds
  double optimality_tolerance = 1e-9;   // accepted dual infeasibility (reduced costs of the wrong sign)
  int max_iterations = 0;               // 0: the backend's default
  // Let the backend rescale rows and columns before solving (CLP: its automatic scaling). Off for small,
  // well-scaled problems solved many times: there the rescaling, and the primal clean-up of unscaled
  // infeasibilities it can leave, cost more than they save (the planner's overhang optimiser: about a third
  // of the time per linear program, modules/planner/README.md).
  bool scale = true;
};

class Solver {
 public:
  virtual ~Solver() = default;
  // Non-virtual: checks availability and the problem, then calls do_solve().
  SolveResult solve(const Problem& problem, const SolverOptions& options = {}) const;

  virtual std::string name() const = 0;
  virtual bool available() const = 0;  // false when the backend was not compiled in
  virtual bool supports_quadratic() const = 0;

 protected:
  virtual SolveResult do_solve(const Problem& problem, const SolverOptions& options) const = 0;
};

// "clp" or "nlopt". Throws std::invalid_argument for an unknown name; returns a stub whose solve() reports
// "not compiled in" when the backend is disabled (BRICKLAYER_WITH_CLP / BRICKLAYER_WITH_NLOPT).
std::unique_ptr<Solver> make_solver(const std::string& name);
std::vector<std::string> solver_names();

}  // namespace bricklayer::core::opt
