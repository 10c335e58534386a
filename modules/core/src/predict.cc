// The three annotators (DESIGN.md "The physics"): balance, paper, exact.
#include "bricklayer/core/predict.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include <nlohmann/json.hpp>

#include "bricklayer/core/contacts.h"
#include "bricklayer/core/program.h"

namespace bricklayer::core {
namespace {

bool is_free(const std::vector<char>& free, size_t i) { return free.empty() || free[i] != 0; }

// Equilibrium rows of every free block: row 2i (force) and 2i+1 (moment about its centre), over variables
// lambda (two per contact, left end then right end). Returns the row index of each block (-1 when fixed).
std::vector<int> add_equilibrium(const ContactGraph& g, const std::vector<char>& free, opt::Problem& problem,
                                 std::vector<int>& contact_var) {
  std::vector<int> row(g.size(), -1);
  for (size_t i = 0; i < g.size(); ++i) {
    if (!is_free(free, i)) continue;
    row[i] = problem.add_row(1.0, 1.0);  // upward contact forces - downward = weight
    problem.add_row(0.0, 0.0);           // moments about the centre
  }
  contact_var.assign(g.contacts.size(), -1);
  for (size_t k = 0; k < g.contacts.size(); ++k) {
    const Contact& c = g.contacts[k];
    if (!is_free(free, static_cast<size_t>(c.upper))) continue;
    const int v = problem.add_variable(0.0, opt::kInfinity, 0.0);
    problem.add_variable(0.0, opt::kInfinity, 0.0);
    contact_var[k] = v;
    for (int end = 0; end < 2; ++end) {
      const double p = end == 0 ? c.left : c.right;
      const int ru = row[static_cast<size_t>(c.upper)];
      problem.set(ru, v + end, 1.0);
      problem.set(ru + 1, v + end, p - g.centre(c.upper));
      if (c.lower != kSurface && row[static_cast<size_t>(c.lower)] >= 0) {
        const int rl = row[static_cast<size_t>(c.lower)];
        problem.set(rl, v + end, -1.0);
        problem.set(rl + 1, v + end, -(p - g.centre(c.lower)));
      }
    }
  }
  return row;
}

// Warm-start basis: for every free block, the forces at the two extreme ends of its support hull (the
// two-point statics of two_point_certificate). With zero-cost forces basic, every reduced cost equals the
// objective coefficient, so the basis is dual feasible and the dual simplex only repairs the few negative
// forces. fallback(i) gives two variables for a block without a usable hull (or {-1, -1}).
template <class Fallback>
std::vector<int> hull_basis(const ContactGraph& g, const std::vector<char>& free, const std::vector<int>& contact_var,
                            Fallback fallback) {
  std::vector<int> basis;
  for (size_t i = 0; i < g.size(); ++i) {
    if (!is_free(free, i)) continue;
    const auto& sup = g.supports[i];
    int left = -1;
    int right = -1;
    if (!sup.empty()) {
      const Contact& cl = g.contacts[static_cast<size_t>(sup.front())];
      const Contact& cr = g.contacts[static_cast<size_t>(sup.back())];
      if (cr.right - cl.left > kContactTolerance) {
        left = contact_var[static_cast<size_t>(sup.front())];
        right = contact_var[static_cast<size_t>(sup.back())] + 1;
      }
    }
    if (left < 0) std::tie(left, right) = fallback(static_cast<int>(i));
    if (left < 0 || right < 0) return {};
    basis.push_back(left);
    basis.push_back(right);
  }
  return basis;
}

opt::SolveResult solve_lp(const opt::Problem& problem, const std::string& solver, const char* what) {
  opt::SolverOptions options;
  // SLSQP often stops (roundoff) with equality residuals of 1e-8..1e-6 on these problems.
  options.feasibility_tolerance = solver == "nlopt" ? 1e-6 : 1e-9;
  const opt::SolveResult result = opt::make_solver(solver)->solve(problem, options);
  if (result.status != opt::SolveStatus::kOptimal) {
    throw SolverError(std::string(what) + " LP (" + solver + "): " + opt::to_string(result.status) + ": " +
                      result.message);
  }
  return result;
}

// A place where the paper annotator may apply a fictitious upward force.
struct Fictitious {
  int block = 0;
  double position = 0.0;  // the block end it acts on
  double pivot = 0.0;     // the support end the block would tip about
  double weight = 1.0;
};

// Fictitious forces at the overhanging end(s) of every block resting on a single block (or on the surface
// alone) and at both ends of a block resting on nothing.
std::vector<Fictitious> fictitious_candidates(const ContactGraph& g) {
  std::vector<Fictitious> out;
  for (int r = 0; r < g.num_rows(); ++r) {
    for (int i : g.rows[static_cast<size_t>(r)]) {
      const auto& sup = g.supports[static_cast<size_t>(i)];
      const double left = g.x[static_cast<size_t>(i)];
      const double right = left + 1.0;
      if (sup.empty()) {
        out.push_back({i, left, right, 1.0});
        out.push_back({i, right, left, 1.0});
      } else if (sup.size() == 1) {
        const Contact& c = g.contacts[static_cast<size_t>(sup[0])];
        if (right - c.right > kContactTolerance) out.push_back({i, right, c.right, 1.0});
        if (c.left - left > kContactTolerance) out.push_back({i, left, c.left, 1.0});
      }
    }
  }
  // Weights (DESIGN.md): supporting a lower block directly must be cheaper than supporting it through a higher
  // one: c_b * x' < c_b' * x for every lower candidate b and higher candidate b', x = |b's end - b's pivot|,
  // x' = |b''s end - b's pivot|. Candidates are in row order, so one pass bottom-up assigns them. Lever arms
  // are floored at 0.01 and weights capped at 1e6 to keep the LP well scaled (README: the cap can bind only on
  // piles with more than ~8 one-on-one rows stacked).
  constexpr double kMinLever = 0.01;
  constexpr double kMaxWeight = 1e6;
  for (size_t k = 0; k < out.size(); ++k) {
    double c = 1.0;
    const int rk = g.row[static_cast<size_t>(out[k].block)];
    for (size_t b = 0; b < k; ++b) {
      if (g.row[static_cast<size_t>(out[b].block)] >= rk) continue;
      const double x = std::max(kMinLever, std::abs(out[b].position - out[b].pivot));
      const double xp = std::abs(out[k].position - out[b].pivot);
      c = std::max(c, 1.5 * out[b].weight * xp / x);
    }
    out[k].weight = std::min(c, kMaxWeight);
  }
  return out;
}

void fill_common(const Stack& stack, Prediction& p) {
  p.blocks.resize(stack.blocks.size());
  for (size_t i = 0; i < stack.blocks.size(); ++i) p.blocks[i].id = stack.blocks[i].id;
  p.overhang = overhang(stack);
  p.score = score_of(p.overhang);
}

void annotate_balance(const ContactGraph& g, const PredictOptions& options, Prediction& p) {
  p.balanced = two_point_certificate(g) || balance_violation(g, options.solver) <= kBalanceTolerance;
  if (!p.balanced) {
    for (auto& b : p.blocks) b.state = BlockState::kCause;
  }
}

// A primal feasible basis for the paper LP, built top-down like the certificate: each block rests on the two
// extreme ends of its support hull; where that needs a negative force, on one support end and one of its
// fictitious forces (or on its two fictitious forces). Empty when some block cannot be carried that way.
std::vector<int> paper_primal_basis(const ContactGraph& g, const std::vector<Fictitious>& candidates,
                                    const std::vector<int>& var, const std::vector<int>& contact_var) {
  std::vector<std::vector<size_t>> of_block(g.size());
  for (size_t k = 0; k < candidates.size(); ++k) of_block[static_cast<size_t>(candidates[k].block)].push_back(k);
  std::vector<double> f(2 * g.contacts.size(), 0.0);
  std::vector<int> basis;
  basis.reserve(2 * g.size());
  for (int r = g.num_rows() - 1; r >= 0; --r) {
    for (int i : g.rows[static_cast<size_t>(r)]) {
      const double c = g.centre(i);
      double load = 1.0;
      double moment = 0.0;
      for (int k : g.carries[static_cast<size_t>(i)]) {
        const Contact& ct = g.contacts[static_cast<size_t>(k)];
        load += f[2 * static_cast<size_t>(k)] + f[2 * static_cast<size_t>(k) + 1];
        moment += f[2 * static_cast<size_t>(k)] * (ct.left - c) + f[2 * static_cast<size_t>(k) + 1] * (ct.right - c);
      }
      const double tol = -1e-9 * load;
      // A support point: position, LP variable, contact-end index (-1 for a fictitious force).
      struct Point {
        double position;
        int variable;
        int end;
      };
      std::vector<Point> points;
      const auto& sup = g.supports[static_cast<size_t>(i)];
      if (!sup.empty()) {
        const int kl = sup.front();
        const int kr = sup.back();
        points.push_back({g.contacts[static_cast<size_t>(kl)].left, contact_var[static_cast<size_t>(kl)], 2 * kl});
        points.push_back({g.contacts[static_cast<size_t>(kr)].right, contact_var[static_cast<size_t>(kr)] + 1, 2 * kr + 1});
      }
      for (size_t k : of_block[static_cast<size_t>(i)]) points.push_back({candidates[k].position, var[k], -1});
      bool placed = false;
      for (size_t a = 0; a < points.size() && !placed; ++a) {
        for (size_t b = a + 1; b < points.size() && !placed; ++b) {
          const Point* p1 = &points[a];
          const Point* p2 = &points[b];
          if (p1->position > p2->position) std::swap(p1, p2);
          const double d1 = p1->position - c;
          const double d2 = p2->position - c;
          if (!(d2 - d1 > kContactTolerance)) continue;
          const double f2 = (moment - load * d1) / (d2 - d1);
          const double f1 = load - f2;
          if (f1 < tol || f2 < tol) continue;
          if (p1->end >= 0) f[static_cast<size_t>(p1->end)] = std::max(0.0, f1);
          if (p2->end >= 0) f[static_cast<size_t>(p2->end)] = std::max(0.0, f2);
          basis.push_back(p1->variable);
          basis.push_back(p2->variable);
          placed = true;
        }
      }
      if (!placed) return {};
    }
  }
  return basis;
}

void annotate_paper(const ContactGraph& g, const PredictOptions& options, Prediction& p) {
  p.balanced = true;
  if (two_point_certificate(g)) return;  // balanced: every fictitious force is zero
  opt::Problem problem;
  std::vector<int> contact_var;
  const std::vector<int> row = add_equilibrium(g, {}, problem, contact_var);
  const std::vector<Fictitious> candidates = fictitious_candidates(g);
  std::vector<int> var(candidates.size());
  for (size_t k = 0; k < candidates.size(); ++k) {
    const Fictitious& f = candidates[k];
    var[k] = problem.add_variable(0.0, opt::kInfinity, f.weight);
    const int r = row[static_cast<size_t>(f.block)];
    problem.set(r, var[k], 1.0);
    problem.set(r + 1, var[k], f.position - g.centre(f.block));
  }
  problem.basis_hint = paper_primal_basis(g, candidates, var, contact_var);
  problem.hint_primal_feasible = !problem.basis_hint.empty();
  if (problem.basis_hint.empty()) {
    problem.basis_hint = hull_basis(g, {}, contact_var, [&](int block) {
      std::pair<int, int> pair{-1, -1};
      for (size_t k = 0; k < candidates.size(); ++k) {
        if (candidates[k].block != block) continue;
        (pair.first < 0 ? pair.first : pair.second) = var[k];
      }
      return pair;
    });
  }
  const opt::SolveResult result = solve_lp(problem, options.solver, "paper annotator");
  p.balanced = true;
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (result.x[static_cast<size_t>(var[k])] > kFictitiousTolerance) {
      p.blocks[static_cast<size_t>(candidates[k].block)].state = BlockState::kCause;
      p.balanced = false;
    }
  }
}

// initial_accelerations() with backend failures reported as SolverError (predict()'s contract).
Accelerations accelerations(const ContactGraph& g, const std::vector<char>& free, QpMethod qp,
                            const std::vector<double>* warm = nullptr) {
  try {
    return initial_accelerations(g, free, qp, true, warm);
  } catch (const std::invalid_argument&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw SolverError(e.what());
  }
}

void annotate_exact(const ContactGraph& g, const PredictOptions& options, Prediction& p) {
  p.balanced = true;
  if (g.size() == 0) return;
  if (two_point_certificate(g)) return;
  if (options.lp_first && balance_violation(g, options.solver) <= kBalanceTolerance) return;
  p.qp = to_string(options.qp);
  const Accelerations full = accelerations(g, {}, options.qp);
  for (size_t i = 0; i < g.size(); ++i) {
    p.blocks[i].accel = full.a[i];
    p.blocks[i].alpha = full.alpha[i];
    if (full.moving(i)) p.blocks[i].state = BlockState::kMoving;
  }
  if (!full.any_moving()) return;  // within tolerance: the QP is the judge of motion
  p.balanced = false;
  // Causes: a block of row r is a cause when it moves with every row below r held fixed. If no block of rows
  // [r, r') moves in the subsystem "rows >= r free", that subsystem's solution is also the solution with rows
  // < r' fixed, so one QP answers every row up to and including its lowest moving row.
  const Accelerations* current = &full;
  Accelerations sub;
  int from_row = 0;
  while (from_row < g.num_rows()) {
    int lowest = -1;
    for (int r = from_row; r < g.num_rows() && lowest < 0; ++r) {
      for (int i : g.rows[static_cast<size_t>(r)]) {
        if (current->moving(static_cast<size_t>(i))) {
          lowest = r;
          break;
        }
      }
    }
    if (lowest < 0) break;
    for (int i : g.rows[static_cast<size_t>(lowest)]) {
      if (current->moving(static_cast<size_t>(i))) p.blocks[static_cast<size_t>(i)].state = BlockState::kCause;
    }
    from_row = lowest + 1;
    if (from_row >= g.num_rows()) break;
    std::vector<char> free(g.size(), 0);
    for (size_t i = 0; i < g.size(); ++i) free[i] = g.row[i] >= from_row ? 1 : 0;
    sub = accelerations(g, free, options.qp, &current->force);
    current = &sub;
  }
}

}  // namespace

std::vector<BlockState> exact_states(const ContactGraph& graph, QpMethod qp) {
  PredictOptions options;
  options.qp = qp;
  Prediction p;
  p.blocks.resize(graph.size());
  annotate_exact(graph, options, p);
  std::vector<BlockState> out(graph.size());
  for (size_t i = 0; i < graph.size(); ++i) out[i] = p.blocks[i].state;
  return out;
}

double balance_violation(const ContactGraph& g, const std::string& solver, const std::vector<char>& free) {
  opt::Problem problem;
  std::vector<int> contact_var;
  const std::vector<int> row = add_equilibrium(g, free, problem, contact_var);
  std::vector<int> slack(static_cast<size_t>(problem.num_rows()));
  for (int r = 0; r < problem.num_rows(); ++r) {
    slack[static_cast<size_t>(r)] = problem.add_variable(0.0, opt::kInfinity, 1.0);
    problem.set(r, slack[static_cast<size_t>(r)], 1.0);
    problem.set(r, problem.add_variable(0.0, opt::kInfinity, 1.0), -1.0);
  }
  problem.basis_hint = hull_basis(g, free, contact_var, [&](int block) {
    const int r = row[static_cast<size_t>(block)];
    return std::pair<int, int>{slack[static_cast<size_t>(r)], slack[static_cast<size_t>(r) + 1]};
  });
  if (problem.num_rows() == 0) return 0.0;
  const opt::SolveResult result = solve_lp(problem, solver, "balance");
  return std::max(0.0, result.objective);
}

std::vector<int64_t> Prediction::causes() const {
  std::vector<int64_t> ids;
  for (const auto& b : blocks) {
    if (b.state == BlockState::kCause) ids.push_back(b.id);
  }
  return ids;
}

std::vector<int64_t> Prediction::moving() const {
  std::vector<int64_t> ids;
  for (const auto& b : blocks) {
    if (b.state != BlockState::kStable) ids.push_back(b.id);
  }
  return ids;
}

double overhang(const Stack& stack) {
  double rightmost = -opt::kInfinity;
  for (const Block& b : stack.blocks) rightmost = std::max(rightmost, b.x + stack.block_length);
  if (stack.blocks.empty()) return 0.0;
  return std::max(0.0, (rightmost - stack.table_edge) / stack.block_length);
}

int32_t score_of(double overhang_in_block_lengths) {
  const double s = std::round(100.0 * overhang_in_block_lengths);
  return static_cast<int32_t>(std::clamp(s, -2e9, 2e9));
}

Prediction predict(const Stack& stack, const PredictOptions& options) {
  if (!(options.position_tolerance >= 0.0 && options.position_tolerance <= kMaxPositionTolerance)) {
    throw std::invalid_argument("position tolerance " + std::to_string(options.position_tolerance) +
                                " block lengths is outside [0, " + std::to_string(kMaxPositionTolerance) + "]");
  }
  validate(stack, options.limits);
  const ContactGraph graph = build_contacts(stack, options.position_tolerance);
  Prediction p;
  p.position_tolerance = options.position_tolerance;
  p.annotator = to_string(options.annotator);
  p.solver = options.solver;
  fill_common(stack, p);
  switch (options.annotator) {
    case Annotator::kBalance: annotate_balance(graph, options, p); break;
    case Annotator::kPaper: annotate_paper(graph, options, p); break;
    case Annotator::kExact:
      p.solver = options.lp_first ? options.solver + "+" + to_string(options.qp) : to_string(options.qp);
      annotate_exact(graph, options, p);
      break;
  }
  return p;
}

nlohmann::json to_json(const Prediction& p) {
  nlohmann::json out;
  out["balanced"] = p.balanced;
  out["unbalanced"] = p.causes();
  out["moving"] = p.moving();
  out["overhang"] = p.overhang;
  out["score"] = p.score;
  out["annotator"] = p.annotator;
  out["solver"] = p.solver;
  if (!p.qp.empty()) out["qp"] = p.qp;
  if (p.position_tolerance > 0.0) out["position_tolerance"] = p.position_tolerance;
  nlohmann::json blocks = nlohmann::json::array();
  for (const auto& b : p.blocks) {
    static const char* const kStates[] = {"stable", "moving", "cause"};
    nlohmann::json jb = {{"id", b.id}, {"state", kStates[static_cast<int>(b.state)]}};
    if (!p.qp.empty()) {
      jb["accel"] = b.accel;
      jb["alpha"] = b.alpha;
    }
    blocks.push_back(std::move(jb));
  }
  out["blocks"] = std::move(blocks);
  return out;
}

Annotator parse_annotator(const std::string& name) {
  if (name == "exact") return Annotator::kExact;
  if (name == "paper") return Annotator::kPaper;
  if (name == "balance") return Annotator::kBalance;
  throw std::invalid_argument("unknown annotator \"" + name + "\" (expected exact, paper or balance)");
}

std::string to_string(Annotator annotator) {
  switch (annotator) {
    case Annotator::kExact: return "exact";
    case Annotator::kPaper: return "paper";
    case Annotator::kBalance: return "balance";
  }
  return "exact";
}

}  // namespace bricklayer::core
