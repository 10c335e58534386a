#include "bricklayer/planner/best_overhang.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "bricklayer/core/predict.h"
#include "bricklayer/core/program.h"

namespace bricklayer::planner {
namespace {

constexpr int kTable = -1;

struct Contact {
  int lower;  // block index or kTable
  int upper;
};

// The problem for one layout: variables v = [x_0..x_{n-1}, f_0, m_0, f_1, m_1, ...].
struct LayoutProblem {
  std::vector<int> rows;
  std::vector<Contact> contacts;
  std::vector<std::pair<int, int>> same_row;  // (left, right) neighbours in one row: x_right - x_left >= 1
  int target = 0;
  std::vector<double> start;  // starting variables (feasibility phase: stay near these positions)
  int n() const { return static_cast<int>(rows.size()); }
  int num_vars() const { return n() + 2 * static_cast<int>(contacts.size()); }
  int f_index(size_t c) const { return n() + 2 * static_cast<int>(c); }
  int m_index(size_t c) const { return n() + 2 * static_cast<int>(c) + 1; }

  int num_inequalities() const {
    int count = static_cast<int>(same_row.size());
    for (const Contact& c : contacts) count += c.lower == kTable ? 3 : 4;
    return count;
  }
};

// A contact that carries force overlaps by at least this (block lengths); the surface likewise (the block's
// left end at most -kMinOverlap). Without it the optimiser leaned blocks on end-to-end touching neighbours
// (overlap 0: no contact for the core, so n = 19, 24 and 28 read unbalanced); with 2e-8 it used overlaps of
// 2e-6..8e-6, where the exact annotator's QP leaves accelerations of 1e-6..7e-6 g, above its 1e-6 motion
// tolerance. DESIGN.md: an overlap of 1e-4 is still a contact. Points of application may still sit exactly
// at a block's end (the 3-block optimum needs that).
constexpr double kMinOverlap = 1e-4;

// The constraints that are bilinear in (position, force), g <= 0: the resultant of contact c lies within
// block b, f*x_b - m (kind 0) and m - f*(x_b + 1) (kind 1); on the surface m (kind 2, linear, but a start
// whose centre of mass is beyond the edge violates it); a loaded contact overlaps by kMinOverlap,
// f*(x_upper - x_lower - 1 + kMinOverlap) (kind 3), f*(x_lower - x_upper - 1 + kMinOverlap) (kind 4), and on
// the surface f*(x_upper + kMinOverlap) (kind 5). These get slacks in the linear programs; the rest
// (equilibrium, neighbours in a row) is kept exactly in every one.
struct Bilinear {
  size_t contact;
  int block;
  int kind;
};

std::vector<Bilinear> bilinear_constraints(const LayoutProblem& p) {
  std::vector<Bilinear> out;
  for (size_t c = 0; c < p.contacts.size(); ++c) {
    for (int b : {p.contacts[c].upper, p.contacts[c].lower})
      if (b != kTable)
        for (int kind : {0, 1}) out.push_back({c, b, kind});
    if (p.contacts[c].lower == kTable) {
      out.push_back({c, kTable, 2});
      out.push_back({c, p.contacts[c].upper, 5});
    } else {
      out.push_back({c, p.contacts[c].upper, 3});
      out.push_back({c, p.contacts[c].upper, 4});
    }
  }
  return out;
}

double violation(const LayoutProblem& p, const Bilinear& g, const std::vector<double>& v) {
  const double f = v[p.f_index(g.contact)], m = v[p.m_index(g.contact)];
  if (g.kind == 2) return m;  // on the surface: m - f * 0 <= 0, linear, but kept elastic like the others
  const double x = v[g.block];
  if (g.kind == 5) return f * (x + kMinOverlap);
  if (g.kind == 3 || g.kind == 4) {
    const double d = v[p.contacts[g.contact].upper] - v[p.contacts[g.contact].lower];
    return f * ((g.kind == 3 ? d : -d) - 1.0 + kMinOverlap);
  }
  return g.kind == 0 ? f * x - m : m - f * (x + 1.0);
}

// Force and moment (about x = 0) balance of every block: [force_0, moment_0, force_1, ...], zero in equilibrium.
std::vector<double> equilibrium_errors(const LayoutProblem& p, const std::vector<double>& v) {
  const int n = p.n();
  std::vector<double> e(2 * n);
  for (int i = 0; i < n; ++i) {
    e[2 * i] = -1.0;
    e[2 * i + 1] = -(v[i] + 0.5);
  }
  for (size_t c = 0; c < p.contacts.size(); ++c) {
    const Contact& k = p.contacts[c];
    e[2 * k.upper] += v[p.f_index(c)];
    e[2 * k.upper + 1] += v[p.m_index(c)];
    if (k.lower != kTable) {
      e[2 * k.lower] -= v[p.f_index(c)];
      e[2 * k.lower + 1] -= v[p.m_index(c)];
    }
  }
  return e;
}

// Largest violation of any constraint (equalities, bilinear and linear inequalities, bounds) at v.
double residual(const LayoutProblem& p, const std::vector<Bilinear>& bilinear, const std::vector<double>& v,
                const std::vector<double>& lower, const std::vector<double>& upper) {
  double r = 0.0;
  for (double e : equilibrium_errors(p, v)) r = std::max(r, std::abs(e));
  for (const Bilinear& g : bilinear) r = std::max(r, violation(p, g, v));
  for (const auto& [left, right] : p.same_row) r = std::max(r, 1.0 + v[left] - v[right]);
  for (size_t i = 0; i < v.size(); ++i) r = std::max({r, lower[i] - v[i], v[i] - upper[i]});
  return r;
}

// Sequential linear programming (an SL1 trust-region method) over the positions x. For fixed positions the
// constraints are linear in the forces, so the merit of positions x is exact and cheap:
//   phi(x) = x_target - mu * V(x),  V(x) = the smallest sum of constraint violations any forces reach at x,
// one linear program (CLP). A step solves the linear program "maximise x_target - mu * sum of slacks" with
// every bilinear constraint linearised at the current point and given a slack, positions moving at most delta
// (forces free); it is taken when phi improves by at least a tenth of what the model predicted, otherwise delta
// shrinks. A second-order correction (one more linear step from the candidate) brings steps that left the
// curved constraint surface back to it: without it the iterates crept along that surface at delta ~ 1e-4.
// mu starts at 1 and grows tenfold whenever the method stops at an infeasible point. Every iterate satisfies
// the equilibrium equations exactly and the answer's residual is measured, not assumed (SLSQP, used before,
// ended most 30-block runs above a 1e-9 residual).
class SequentialLp {
 public:
  SequentialLp(const LayoutProblem& p, std::vector<double> lower, std::vector<double> upper)
      : p_(p), bilinear_(bilinear_constraints(p)), lower_(std::move(lower)), upper_(std::move(upper)),
        solver_(core::opt::make_solver("clp")) {
    if (!solver_->available())
      throw std::runtime_error("optimise_layout needs the core's clp backend, which was not compiled in "
                               "(install coinor-libclp-dev and configure with -DBRICKLAYER_WITH_CLP=ON)");
    // CLP's own default tolerances (what the optimiser used before it went through the adapter; every answer's
    // residual is measured anyway). No scaling: every coefficient is between 1e-4 and a few times n, and
    // CLP's rescaling plus the clean-up it needed made each program about a third slower (README).
    options_.feasibility_tolerance = 1e-7;
    options_.optimality_tolerance = 1e-7;
    options_.scale = false;
  }

  struct Outcome {
    std::vector<double> v;
    double residual = 0.0;
    int iterations = 0;
    int linear_programs = 0;
    int failed_programs = 0;
  };

  Outcome run(std::vector<double> v, int max_iterations) {
    double mu = 1.0;
    double delta = 0.2;
    int it = 0;
    best_forces(v, mu);
    double merit = merit_of(v, mu);
    std::vector<double> next;
    while (it < max_iterations) {
      ++it;
      double model_value = 0.0;
      if (!solve(v, delta, mu, next, model_value)) {
        delta *= 0.25;
        if (delta < 1e-12) break;
        continue;
      }
      const double predicted = model_value - merit;
      if (predicted <= 1e-13 * (1.0 + std::abs(merit)) || delta < 1e-11) {
        // Stationary for this penalty: done if feasible, else weigh violations more.
        if (total_violation(v) <= 1e-12 || mu >= 1e5) break;
        mu *= 10.0;
        merit = merit_of(v, mu);
        delta = std::max(delta, 1e-3);
        continue;
      }
      best_forces(next, mu);
      double candidate = merit_of(next, mu);
      if ((candidate - merit) / predicted < 0.1) {  // second-order correction, judged by the first prediction
        std::vector<double> corrected;
        double ignored = 0.0;
        if (solve(next, delta, mu, corrected, ignored)) {
          best_forces(corrected, mu);
          const double corrected_merit = merit_of(corrected, mu);
          if (corrected_merit > candidate) {
            candidate = corrected_merit;
            next.swap(corrected);
          }
        }
      }
      const double ratio = (candidate - merit) / predicted;
      if (ratio >= 0.1) {
        double step = 0.0;
        for (int i = 0; i < p_.n(); ++i) step = std::max(step, std::abs(next[i] - v[i]));
        v.swap(next);
        merit = candidate;
        if (ratio > 0.75 && step > 0.99 * delta) delta = std::min(2.0 * delta, 1.0);
      } else {
        delta *= 0.25;
      }
    }
    return {v, residual(p_, bilinear_, v, lower_, upper_), it, linear_programs_, failed_programs_};
  }

 private:
  // Sum of the violations of the bilinear constraints and of the equilibrium equations (the start point
  // does not satisfy the moment equations; every linear program's answer does).
  double total_violation(const std::vector<double>& v) const {
    double sum = 0.0;
    for (const Bilinear& g : bilinear_) sum += std::max(0.0, violation(p_, g, v));
    for (double e : equilibrium_errors(p_, v)) sum += std::abs(e);
    return sum;
  }
  double merit_of(const std::vector<double>& v, double mu) const { return v[p_.target] - mu * total_violation(v); }

  // Replaces the forces in v by the least violating ones for its positions (exact: linear for fixed x).
  void best_forces(std::vector<double>& v, double mu) {
    std::vector<double> fixed_x;
    double ignored = 0.0;
    if (solve(v, 0.0, mu, fixed_x, ignored)) v.swap(fixed_x);
  }

  // The linear program at v; next = its solution, model_value = x_target - mu * sum of slacks there.
  // Every program of one run has the same shape (variables, slacks, rows), so each starts from the last
  // optimal basis.
  bool solve(const std::vector<double>& v, double delta, double mu, std::vector<double>& next, double& model_value) {
    using core::opt::kInfinity;
    const int n = p_.n();
    const int nv = p_.num_vars();
    const int ns = static_cast<int>(bilinear_.size());
    core::opt::Problem& lp = lp_;
    lp.lower.assign(lower_.begin(), lower_.end());
    lp.upper.assign(upper_.begin(), upper_.end());
    lp.cost.assign(static_cast<size_t>(nv), 0.0);
    for (int i = 0; i < n; ++i) {
      lp.lower[i] = std::max(lower_[i], v[i] - delta);
      lp.upper[i] = std::min(upper_[i], v[i] + delta);
    }
    for (int k = 0; k < ns; ++k) lp.add_variable(0.0, kInfinity, mu);  // slack of bilinear constraint k
    lp.cost[p_.target] = -1.0;
    lp.row_lower.clear();
    lp.row_upper.clear();
    lp.a.clear();
    for (int i = 0; i < n; ++i) {  // force and moment equilibrium of block i
      const int force = lp.add_row(1.0, 1.0), moment = lp.add_row(0.5, 0.5);
      for (size_t c = 0; c < p_.contacts.size(); ++c) {
        const Contact& k = p_.contacts[c];
        const double sign = k.upper == i ? 1.0 : (k.lower == i ? -1.0 : 0.0);
        if (sign == 0.0) continue;
        lp.set(force, p_.f_index(c), sign);
        lp.set(moment, p_.m_index(c), sign);
      }
      lp.set(moment, i, -1.0);
    }
    for (int k = 0; k < ns; ++k) {  // each linearised bilinear constraint, <= its bound with slack s_k
      const Bilinear& g = bilinear_[k];
      const int fi = p_.f_index(g.contact), mi = p_.m_index(g.contact);
      int row = 0;
      if (g.kind == 2) {  // m - s <= 0
        row = lp.add_row(-kInfinity, 0.0);
        lp.set(row, mi, 1.0);
      } else if (g.kind == 5) {  // f0 x + (x0 + o) f - s <= f0 x0
        const double f0 = v[fi], x0 = v[g.block];
        row = lp.add_row(-kInfinity, f0 * x0);
        lp.set(row, g.block, f0);
        lp.set(row, fi, x0 + kMinOverlap);
      } else if (g.kind == 3 || g.kind == 4) {  // d = +-(x_u - x_l): f0 d + (d0 - 1 + o) f - s <= f0 d0
        const double sign = g.kind == 3 ? 1.0 : -1.0;
        const int u = p_.contacts[g.contact].upper, l = p_.contacts[g.contact].lower;
        const double f0 = v[fi], d0 = sign * (v[u] - v[l]);
        row = lp.add_row(-kInfinity, f0 * d0);
        lp.set(row, u, sign * f0);
        lp.set(row, l, -sign * f0);
        lp.set(row, fi, d0 - 1.0 + kMinOverlap);
      } else if (g.kind == 0) {  // f0 x + x0 f - m - s <= f0 x0
        const double f0 = v[fi], x0 = v[g.block];
        row = lp.add_row(-kInfinity, f0 * x0);
        lp.set(row, g.block, f0);
        lp.set(row, fi, x0);
        lp.set(row, mi, -1.0);
      } else {  // m - f0 x - (x0 + 1) f - s <= -f0 x0
        const double f0 = v[fi], x0 = v[g.block];
        row = lp.add_row(-kInfinity, -f0 * x0);
        lp.set(row, g.block, -f0);
        lp.set(row, fi, -(x0 + 1.0));
        lp.set(row, mi, 1.0);
      }
      lp.set(row, nv + k, -1.0);
    }
    for (const auto& [left, right] : p_.same_row) {  // x_left + 1 <= x_right
      const int row = lp.add_row(-kInfinity, -1.0);
      lp.set(row, left, 1.0);
      lp.set(row, right, -1.0);
    }
    core::opt::SolveResult result = solver_->solve(lp, options_);
    ++linear_programs_;
    if (result.status != core::opt::SolveStatus::kOptimal) {
      ++failed_programs_;
      lp.warm_start = {};  // start the next one afresh
      return false;
    }
    lp.warm_start = std::move(result.basis);
    next.assign(result.x.begin(), result.x.begin() + nv);
    double slack = 0.0;
    for (int k = 0; k < ns; ++k) slack += result.x[nv + k];
    model_value = next[p_.target] - mu * slack;
    return true;
  }

  const LayoutProblem& p_;
  std::vector<Bilinear> bilinear_;
  std::vector<double> lower_, upper_;
  std::unique_ptr<core::opt::Solver> solver_;
  core::opt::SolverOptions options_;
  core::opt::Problem lp_;  // the last linear program; its warm_start is the last optimal basis
  int linear_programs_ = 0, failed_programs_ = 0;
};

std::vector<PlacedBlock> sorted_blocks(std::vector<PlacedBlock> blocks) {
  std::sort(blocks.begin(), blocks.end(), [](const PlacedBlock& a, const PlacedBlock& b) {
    return a.row != b.row ? a.row < b.row : a.x < b.x;
  });
  return blocks;
}

int rightmost(const std::vector<PlacedBlock>& blocks) {
  int best = 0;
  for (size_t i = 1; i < blocks.size(); ++i)
    if (blocks[i].x > blocks[best].x) best = static_cast<int>(i);
  return best;
}

// Runs task(0..count-1) on up to jobs threads. Each task writes only its own result slot and callers consume
// the slots in index order, so the search's answer does not depend on jobs (every optimisation owns its solver;
// the random draws all happen before, on the calling thread).
void for_each_index(size_t count, int jobs, const std::function<void(size_t)>& task) {
  const size_t threads = std::min<size_t>(count, static_cast<size_t>(std::max(1, jobs)));
  if (threads <= 1) {
    for (size_t i = 0; i < count; ++i) task(i);
    return;
  }
  std::atomic<size_t> next{0};
  std::exception_ptr failure;
  std::atomic<bool> failed{false};
  auto work = [&] {
    for (size_t i = next++; i < count && !failed; i = next++) {
      try {
        task(i);
      } catch (...) {
        if (!failed.exchange(true)) failure = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

// optimise_layout of every layout (each towards its rightmost block), in the layouts' order.
std::vector<std::optional<OverhangStack>> optimise_layouts(const std::vector<std::vector<PlacedBlock>>& layouts,
                                                           double tolerance, int jobs) {
  std::vector<std::optional<OverhangStack>> out(layouts.size());
  for_each_index(layouts.size(), jobs,
                 [&](size_t i) { out[i] = optimise_layout(layouts[i], rightmost(layouts[i]), tolerance); });
  return out;
}

}  // namespace

std::optional<OverhangStack> optimise_layout(const std::vector<PlacedBlock>& start_unsorted, int target,
                                             double tolerance, OptimiseStats* stats) {
  if (stats) *stats = {};
  if (start_unsorted.empty()) return std::nullopt;
  if (target < 0 || target >= static_cast<int>(start_unsorted.size()))
    throw std::invalid_argument("optimise_layout: target " + std::to_string(target) + " out of range");
  for (const PlacedBlock& b : start_unsorted)
    if (b.row < 0 || !std::isfinite(b.x))
      throw std::invalid_argument("optimise_layout: rows must be >= 0 and positions finite");
  // Sort while remembering the target.
  std::vector<int> order(start_unsorted.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const PlacedBlock &pa = start_unsorted[a], &pb = start_unsorted[b];
    return pa.row != pb.row ? pa.row < pb.row : pa.x < pb.x;
  });
  std::vector<PlacedBlock> start;
  LayoutProblem problem;
  for (size_t i = 0; i < order.size(); ++i) {
    start.push_back(start_unsorted[order[i]]);
    if (order[i] == target) problem.target = static_cast<int>(i);
  }
  const int n = static_cast<int>(start.size());
  // Neighbours in a row start at least one length apart (the linear programs keep them so).
  for (int i = 1; i < n; ++i)
    if (start[i].row == start[i - 1].row && start[i].x < start[i - 1].x + 1.0) start[i].x = start[i - 1].x + 1.0;
  for (const PlacedBlock& b : start) problem.rows.push_back(b.row);
  for (int i = 0; i < n; ++i) {
    if (start[i].row == 0) problem.contacts.push_back({kTable, i});
    if (i + 1 < n && start[i + 1].row == start[i].row) problem.same_row.emplace_back(i, i + 1);
  }
  // Possible supports of every block above row 0: the blocks of the row below within reach (forces of pairs
  // that end up not overlapping are held at zero by the interval constraints), at least the nearest one.
  for (int j = 0; j < n; ++j) {
    if (start[j].row == 0) continue;
    int nearest = -1;
    bool any = false;
    for (int i = 0; i < n; ++i) {
      if (start[i].row != start[j].row - 1) continue;
      if (nearest < 0 || std::abs(start[i].x - start[j].x) < std::abs(start[nearest].x - start[j].x)) nearest = i;
      if (std::abs(start[i].x - start[j].x) < 1.6) {
        problem.contacts.push_back({i, j});
        any = true;
      }
    }
    if (nearest < 0)
      throw std::invalid_argument("optimise_layout: row " + std::to_string(start[j].row) + " has no row below");
    if (!any) problem.contacts.push_back({nearest, j});
  }

  const int nv = problem.num_vars();
  std::vector<double> v(nv, 0.0), lower(nv), upper(nv);
  const double span = n + 2.0;
  for (int i = 0; i < n; ++i) {
    v[i] = start[i].x;
    lower[i] = -span;
    upper[i] = span;
  }
  for (size_t c = 0; c < problem.contacts.size(); ++c) {
    lower[problem.f_index(c)] = 0.0;
    upper[problem.f_index(c)] = n + 1.0;
    lower[problem.m_index(c)] = -(n + 1.0) * span;
    upper[problem.m_index(c)] = (n + 1.0) * span;
  }
  // Start forces: each block's load (own weight + what rests on it) shared among its supports in proportion
  // to the overlap, acting at the overlap's middle: the first linearisation then starts from plausible forces.
  {
    std::vector<double> load(n, 1.0);
    for (int i = n - 1; i >= 0; --i) {
      std::vector<std::pair<size_t, double>> below;  // contact, overlap
      double total = 0.0;
      for (size_t c = 0; c < problem.contacts.size(); ++c) {
        const Contact& k = problem.contacts[c];
        if (k.upper != i) continue;
        const double lo = k.lower == kTable ? start[i].x : std::max(start[i].x, start[k.lower].x);
        const double hi = k.lower == kTable ? std::min(start[i].x + 1.0, 0.0) : std::min(start[i].x, start[k.lower].x) + 1.0;
        below.emplace_back(c, std::max(hi - lo, 1e-3));
        total += below.back().second;
      }
      for (const auto& [c, overlap] : below) {
        const Contact& k = problem.contacts[c];
        const double f = load[i] * overlap / total;
        const double lo = k.lower == kTable ? start[i].x : std::max(start[i].x, start[k.lower].x);
        v[problem.f_index(c)] = f;
        v[problem.m_index(c)] = std::clamp(f * (lo + 0.5 * overlap), lower[problem.m_index(c)], upper[problem.m_index(c)]);
        if (k.lower != kTable) load[k.lower] += f;
      }
    }
  }

  SequentialLp slp(problem, lower, upper);
  const SequentialLp::Outcome result = slp.run(v, 400);
  if (stats) *stats = {result.iterations, result.linear_programs, result.failed_programs};
  if (!(result.residual <= tolerance)) return std::nullopt;

  OverhangStack out;
  out.residual = result.residual;
  for (int i = 0; i < n; ++i) out.blocks.push_back({start[i].row, result.v[i]});
  out.blocks = sorted_blocks(out.blocks);
  double best = -1e300;
  for (const PlacedBlock& b : out.blocks) best = std::max(best, b.x + 1.0);
  out.overhang = best;
  return out;
}

namespace {

// Where one more block could go: each end of each row, gaps, and a new top row over each top block.
std::vector<std::vector<PlacedBlock>> grown(const std::vector<PlacedBlock>& layout) {
  std::vector<std::vector<PlacedBlock>> out;
  int top = 0;
  for (const PlacedBlock& b : layout) top = std::max(top, b.row);
  auto with = [&](int row, double x) {
    std::vector<PlacedBlock> next = layout;
    next.push_back({row, x});
    out.push_back(sorted_blocks(std::move(next)));
  };
  for (int r = 0; r <= top; ++r) {
    std::vector<double> xs;
    for (const PlacedBlock& b : layout)
      if (b.row == r) xs.push_back(b.x);
    if (xs.empty()) continue;
    std::sort(xs.begin(), xs.end());
    if (r > 0) with(r, xs.front() - 1.02);
    with(r, xs.back() + 1.02);
    for (size_t i = 0; i + 1 < xs.size(); ++i)
      if (xs[i + 1] - xs[i] >= 2.0) with(r, 0.5 * (xs[i] + xs[i + 1]));
  }
  for (const PlacedBlock& b : layout)
    if (b.row == top) {
      with(top + 1, b.x - 0.5);
      with(top + 1, b.x);
      with(top + 1, b.x + 0.5);
    }
  return out;
}

// Brick-wall seeds with random row profiles (one block on the surface, rows widening then narrowing, rows
// stepping right up to the principal row and back left above it): large optimal stacks are wide walls with
// counterweights on top, which growing block by block does not always reach.
std::vector<std::vector<PlacedBlock>> staircase_seeds(int n, int count, std::mt19937_64& rng) {
  std::vector<std::vector<PlacedBlock>> out;
  const int base_rows = std::max(2, static_cast<int>(std::lround(std::sqrt(2.0 * n))));
  for (int k = 0; k < count; ++k) {
    const int rows = std::max(2, base_rows + static_cast<int>(rng() % 4) - 1);
    std::vector<int> counts(rows, 1);
    int total = rows;
    while (total > n) {  // too many rows for n blocks: drop rows
      counts.pop_back();
      --total;
    }
    const int nr = static_cast<int>(counts.size());
    while (total < n) {  // add blocks, preferring the middle rows, at most one more than the row below
      const int r = 1 + static_cast<int>(rng() % std::max(1, nr - 1));
      if (r >= nr) continue;
      if (counts[r] < counts[r - 1] + 1 || rng() % 8 == 0) {
        ++counts[r];
        ++total;
      }
    }
    const int principal = nr <= 2 ? nr - 1 : 1 + static_cast<int>(rng() % (nr - 1));
    std::uniform_real_distribution<double> jitter(-0.1, 0.1);
    std::vector<PlacedBlock> seed;
    double right = 0.3;
    for (int r = 0; r < nr; ++r) {
      right = r == 0 ? 0.3 : (r <= principal ? right + 0.25 : right - 0.5);
      for (int j = 0; j < counts[r]; ++j) seed.push_back({r, right - 1.0 - j + jitter(rng)});
    }
    for (int r = 0; r < nr; ++r) {  // keep each row's blocks clear of each other after the jitter
      std::vector<double*> xs;
      for (PlacedBlock& b : seed)
        if (b.row == r) xs.push_back(&b.x);
      std::sort(xs.begin(), xs.end(), [](double* a, double* b) { return *a > *b; });
      for (size_t i = 1; i < xs.size(); ++i) *xs[i] = std::min(*xs[i], *xs[i - 1] - 1.0);
    }
    out.push_back(sorted_blocks(std::move(seed)));
  }
  return out;
}

// Walls whose rows grow by at most one block and whose blocks all overlap the row below.
std::vector<std::vector<PlacedBlock>> supported_wall_seeds(int n, int count, std::mt19937_64& rng) {
  std::vector<std::vector<PlacedBlock>> out;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < count; ++k) {
    // Row widths: one block on the surface, growing by at most one per row up to a random width.
    const int widest = 2 + static_cast<int>(rng() % 4);
    std::vector<int> counts{1};
    int total = 1;
    while (total < n) {
      int c = counts.back();
      if (c < widest && unit(rng) < 0.7) ++c;
      c = std::min(c, n - total);
      counts.push_back(c);
      total += c;
    }
    const int rows = static_cast<int>(counts.size());
    const int on_top = rows > 3 ? 1 + static_cast<int>(rng() % 2) : (rows > 1 ? 1 : 0);
    const int principal = rows - 1 - on_top;
    // Right ends step right up to the principal row and back left above it; every block overlaps the row
    // below (so the start forces can carry every block).
    std::vector<PlacedBlock> seed;
    double right = 0.2 + 0.1 * unit(rng), left = right - 1.0;
    seed.push_back({0, left});
    for (int r = 1; r < rows; ++r) {
      const double prev_right = right, prev_left = left;
      if (r <= principal) right += counts[r] > counts[r - 1] ? 0.35 + 0.25 * unit(rng) : 0.1 + 0.3 * unit(rng);
      else right -= 0.4 + 0.4 * unit(rng);
      right = std::min(right, prev_right + 0.9);
      right = std::max(right, prev_left - 0.9 + counts[r]);  // leftmost block still overlaps the row below
      left = right - counts[r];
      for (int j = 0; j < counts[r]; ++j) seed.push_back({r, left + j});
    }
    out.push_back(sorted_blocks(std::move(seed)));
  }
  return out;
}

// Both families, alternating.
std::vector<std::vector<PlacedBlock>> wall_seeds(int n, int count, std::mt19937_64& rng) {
  std::vector<std::vector<PlacedBlock>> out;
  for (int k = 0; k < count; ++k) {
    auto one = k % 2 == 0 ? staircase_seeds(n, 1, rng) : supported_wall_seeds(n, 1, rng);
    out.push_back(std::move(one.front()));
  }
  return out;
}

}  // namespace

std::vector<std::vector<PlacedBlock>> wall_layouts(int n, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  return wall_seeds(n, count, rng);
}

namespace {

std::string shape_key(const OverhangStack& s) {
  std::string key;
  int row = -1, count = 0;
  for (const PlacedBlock& b : s.blocks) {
    if (b.row != row) {
      if (row >= 0) key += std::to_string(count) + ",";
      row = b.row;
      count = 0;
    }
    ++count;
  }
  key += std::to_string(count);
  return key;
}

}  // namespace

namespace {

// The blocks a move may take away: the ends of each row (inner blocks of a wall carry the rows above).
std::vector<int> movable_blocks(const std::vector<PlacedBlock>& blocks) {
  std::vector<int> out;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const bool first = i == 0 || blocks[i - 1].row != blocks[i].row;
    const bool last = i + 1 == blocks.size() || blocks[i + 1].row != blocks[i].row;
    if (first || last) out.push_back(static_cast<int>(i));
  }
  return out;
}

// Paterson & Zwick's local improvement over combinatorial types: take one block away (an end of a row) and
// put it anywhere one more block could go, re-optimise from the current positions (nearly balanced, so
// each try is cheap), keep the first improvement and start again; at most budget optimisations, in a seeded
// order. The tries run jobs at a time; the first improving one in the seeded order is taken and the tries
// after it count as unspent, so the answer is the one-thread answer.
OverhangStack improve_by_moves(OverhangStack best, int budget, double tolerance, std::mt19937_64& rng, int jobs) {
  bool improved = true;
  while (improved && budget > 0) {
    improved = false;
    std::vector<std::vector<PlacedBlock>> tries;
    const int top = best.blocks.back().row;
    for (int j : movable_blocks(best.blocks)) {
      std::vector<PlacedBlock> rest = best.blocks;
      const PlacedBlock moved = rest[j];
      rest.erase(rest.begin() + j);
      const bool alone = std::none_of(rest.begin(), rest.end(), [&](const PlacedBlock& b) { return b.row == moved.row; });
      if (rest.empty() || (alone && moved.row != top)) continue;  // the rows above would lose their support
      for (auto& layout : grown(rest)) {
        // Skip putting the block back where it was.
        bool same = false;
        for (const PlacedBlock& b : layout)
          same = same || (b.row == moved.row && std::abs(b.x - moved.x) < 0.05);
        if (!same) tries.push_back(std::move(layout));
      }
    }
    std::shuffle(tries.begin(), tries.end(), rng);
    const size_t batch = static_cast<size_t>(std::max(1, jobs));
    for (size_t start = 0; start < tries.size() && budget > 0 && !improved; start += batch) {
      const size_t count = std::min({batch, tries.size() - start, static_cast<size_t>(budget)});
      const std::vector<std::vector<PlacedBlock>> some(tries.begin() + static_cast<long>(start),
                                                       tries.begin() + static_cast<long>(start + count));
      const auto results = optimise_layouts(some, tolerance, jobs);
      for (size_t k = 0; k < count; ++k) {
        --budget;
        if (results[k] && results[k]->overhang > best.overhang + 1e-9) {
          best = *results[k];
          improved = true;
          break;
        }
      }
    }
  }
  return best;
}

// s with one more block lying on the surface far to the left: balanced, the same overhang.
OverhangStack with_surface_block(OverhangStack s) {
  double left = 0.0;
  for (const PlacedBlock& b : s.blocks) left = std::min(left, b.x);
  s.blocks.insert(s.blocks.begin(), PlacedBlock{0, left - 2.0});
  return s;
}

}  // namespace

namespace {

// The stacks of a ranking (best first), at most kept of each overhang (equal to 1e-9); kept 0 keeps all.
std::vector<OverhangStack> few_alike(const std::vector<OverhangStack>& ranked, int kept) {
  if (kept <= 0) return ranked;
  std::vector<OverhangStack> out;
  for (const OverhangStack& s : ranked) {
    const auto alike = std::count_if(out.begin(), out.end(), [&](const OverhangStack& o) {
      return std::abs(o.overhang - s.overhang) <= 1e-9;
    });
    if (alike < kept) out.push_back(s);
  }
  return out;
}

// The row of a stack's rightmost block (its load point: what is above it is counterweight).
int principal_row(const OverhangStack& s) {
  const PlacedBlock* right = &s.blocks.front();
  for (const PlacedBlock& b : s.blocks)
    if (b.x > right->x) right = &b;
  return right->row;
}

// Up to `extra` more layouts for the beam from the ranking (best first), each the best one whose rightmost
// block is on a row none in the beam has: stacks whose load sits higher grow faster but start behind, so a
// beam of the best few alone drops them before they overtake.
void add_variety(const std::vector<OverhangStack>& ranked, int extra, std::vector<OverhangStack>& beam) {
  std::set<int> rows;
  for (const OverhangStack& s : beam) rows.insert(principal_row(s));
  for (size_t i = beam.size(); i < ranked.size() && extra > 0; ++i)
    if (rows.insert(principal_row(ranked[i])).second) {
      beam.push_back(ranked[i]);
      --extra;
    }
}

}  // namespace

std::optional<OverhangStack> best_one_block_less(const OverhangStack& s, double tolerance, int jobs) {
  std::optional<OverhangStack> best;
  if (s.blocks.size() < 2) return best;
  const int top = s.blocks.back().row;
  std::vector<std::vector<PlacedBlock>> layouts;
  for (size_t j = 0; j < s.blocks.size(); ++j) {
    std::vector<PlacedBlock> rest = s.blocks;
    const PlacedBlock removed = rest[j];
    rest.erase(rest.begin() + static_cast<long>(j));
    const bool alone = std::none_of(rest.begin(), rest.end(), [&](const PlacedBlock& b) { return b.row == removed.row; });
    if (alone && removed.row != top) continue;  // the rows above would lose their support
    layouts.push_back(std::move(rest));
  }
  for (auto& result : optimise_layouts(layouts, tolerance, jobs))
    if (result && (!best || result->overhang > best->overhang)) best = std::move(result);
  return best;
}

bool annotator_balanced(const OverhangStack& s) {
  core::Stack stack;  // block length 1, edge at 0, height 1/3 (balance itself does not depend on the height)
  int64_t id = 1;
  for (const PlacedBlock& b : s.blocks) stack.blocks.push_back({id++, b.row, b.x});
  return core::predict(stack).balanced;
}

std::vector<OverhangStack> search_best_overhang(int n_max, const OverhangSearchOptions& options,
                                                const std::function<void(int, const OverhangStack&)>& progress,
                                                const std::function<void(const OverhangSearchState&)>& checkpoint) {
  if (n_max < 1) throw std::invalid_argument("search_best_overhang: n_max must be at least 1");
  std::mt19937_64 rng(options.seed);
  std::vector<OverhangStack> best_per_n;
  std::vector<OverhangStack> beam;
  int first_new = 0;  // the first n this run computes; shrink leaves the rows below it alone
  if (options.continue_from) {
    if (!options.resume_from.empty())
      throw std::invalid_argument("search_best_overhang: continue_from and resume_from exclude each other");
    const OverhangSearchState& state = *options.continue_from;
    best_per_n = state.best_per_n;
    beam = state.beam;
    first_new = state.first_new;
    std::istringstream engine(state.rng);
    engine >> rng;
    if (!engine || best_per_n.empty() || beam.empty() || first_new < 2)
      throw std::invalid_argument("search_best_overhang: continue_from is not a search's state (" +
                                  std::string(!engine ? "unreadable random engine state" : "empty rows or beam") + ")");
    for (const OverhangStack& s : beam)
      if (s.blocks.size() != best_per_n.size())
        throw std::invalid_argument("search_best_overhang: continue_from's beam does not hold " +
                                    std::to_string(best_per_n.size()) + "-block layouts");
  } else if (options.resume_from.empty()) {
    OverhangStack one;
    one.blocks = {{0, -0.5}};
    one.overhang = 0.5;
    best_per_n.push_back(one);
  } else {
    best_per_n = options.resume_from;
  }
  for (size_t k = 0; k < best_per_n.size(); ++k) {
    if (best_per_n[k].blocks.size() != k + 1)
      throw std::invalid_argument("search_best_overhang: row " + std::to_string(k + 1) + " of the given stacks does not have " +
                                  std::to_string(k + 1) + " blocks");
    if (progress) progress(static_cast<int>(k + 1), best_per_n[k]);
  }
  if (!options.continue_from) {
    beam.push_back(best_per_n.back());
    first_new = static_cast<int>(best_per_n.size()) + 1;
  }
  for (int n = static_cast<int>(best_per_n.size()) + 1; n <= n_max; ++n) {
    std::map<std::string, OverhangStack> found;  // the best layout of each row profile at this n
    // Optimises the seeds (on options.jobs threads) and files the answers in the seeds' order.
    auto consider = [&](const std::vector<std::vector<PlacedBlock>>& seeds) {
      for (auto& result : optimise_layouts(seeds, options.tolerance, options.jobs)) {
        if (!result) continue;
        auto [it, inserted] = found.emplace(shape_key(*result), *result);
        if (!inserted && result->overhang > it->second.overhang) it->second = *result;
      }
    };
    // Best first; equal overhangs keep the row profiles' order (std::sort leaves the order of equals to the
    // library, and the beam search is path-dependent).
    auto ranked_candidates = [&] {
      std::vector<OverhangStack> out;
      for (auto& [key, s] : found) out.push_back(s);
      std::stable_sort(out.begin(), out.end(),
                       [](const OverhangStack& a, const OverhangStack& b) { return a.overhang > b.overhang; });
      return out;
    };
    {
      std::vector<std::vector<PlacedBlock>> seeds;
      for (const OverhangStack& s : beam)
        for (auto& seed : grown(s.blocks)) seeds.push_back(std::move(seed));
      if (n >= 8)
        for (auto& seed : wall_seeds(n, options.wall_seeds, rng)) seeds.push_back(std::move(seed));
      if (static_cast<size_t>(n) <= options.start_layouts.size() && !options.start_layouts[n - 1].blocks.empty())
        seeds.push_back(options.start_layouts[n - 1].blocks);
      consider(seeds);
    }
    // Seeded restarts around the best few.
    std::vector<OverhangStack> ranked = few_alike(ranked_candidates(), options.alike);
    {
      std::normal_distribution<double> noise(0.0, 0.08);
      const size_t top_few = std::min<size_t>(ranked.size(), 2);
      std::vector<std::vector<PlacedBlock>> seeds;
      for (size_t i = 0; i < top_few; ++i)
        for (int k = 0; k < options.perturbations; ++k) {
          std::vector<PlacedBlock> seed = ranked[i].blocks;
          for (PlacedBlock& b : seed) b.x += noise(rng);
          seeds.push_back(sorted_blocks(seed));
        }
      consider(seeds);
    }
    ranked = few_alike(ranked_candidates(), options.alike);
    // Polish the best: positions moved, so rebuild the contact set from them and optimise again.
    for_each_index(std::min<size_t>(ranked.size(), options.beam), options.jobs, [&](size_t i) {
      for (int round = 0; round < 3; ++round) {
        auto again = optimise_layout(ranked[i].blocks, rightmost(ranked[i].blocks), options.tolerance);
        if (!again || again->overhang <= ranked[i].overhang + 1e-9) break;
        ranked[i] = *again;
      }
    });
    std::sort(ranked.begin(), ranked.end(),
              [](const OverhangStack& a, const OverhangStack& b) { return a.overhang > b.overhang; });
    {
      // Always a candidate: the best of n-1 plus a block lying on the surface far to the left (still balanced),
      // so the table never decreases with n even when nothing better converges.
      const OverhangStack fallback = with_surface_block(best_per_n.back());
      auto at = std::find_if(ranked.begin(), ranked.end(),
                             [&](const OverhangStack& r) { return r.overhang < fallback.overhang; });
      ranked.insert(at, fallback);
    }
    if (options.moves > 0 && n >= 4) {
      OverhangStack moved = improve_by_moves(ranked.front(), options.moves, options.tolerance, rng, options.jobs);
      if (moved.overhang > ranked.front().overhang) ranked.insert(ranked.begin(), moved);
    }
    ranked = few_alike(ranked, options.alike);
    beam.assign(ranked.begin(), ranked.begin() + std::min<size_t>(ranked.size(), options.beam));
    if (n >= options.variety_from) add_variety(ranked, options.variety, beam);
    // The row is the best the exact annotator calls balanced (annotator_balanced). The beam, which the next n
    // grows, stays as ranked: a stack the optimiser balanced is still a good start. The fallback is balanced.
    {
      auto shown = std::find_if(ranked.begin(), ranked.end(), [](const OverhangStack& s) { return annotator_balanced(s); });
      best_per_n.push_back(shown != ranked.end() ? *shown : with_surface_block(best_per_n.back()));
    }
    if (options.shrink) {
      // Back down: the best n stack minus a block may beat the best n-1 one, and that one minus a block the
      // n-2 one, ... (only rows this run computed: resumed rows stay as given).
      int lowest = n;
      for (int k = n; k - 1 > first_new - 1 && k >= 2; --k) {
        auto smaller = best_one_block_less(best_per_n[k - 1], options.tolerance, options.jobs);
        if (!smaller || smaller->overhang <= best_per_n[k - 2].overhang + 1e-9 || !annotator_balanced(*smaller)) break;
        best_per_n[k - 2] = *smaller;
        lowest = k - 1;
      }
      // A row that improved may now beat the rows above it: they get it plus a block on the surface.
      for (int k = lowest + 1; k <= n; ++k)
        if (best_per_n[k - 1].overhang < best_per_n[k - 2].overhang)
          best_per_n[k - 1] = with_surface_block(best_per_n[k - 2]);
      if (best_per_n.back().overhang > beam.front().overhang) beam.insert(beam.begin(), best_per_n.back());
      if (progress)
        for (int k = lowest; k < n; ++k) progress(k, best_per_n[k - 1]);
    }
    if (progress) progress(n, best_per_n.back());
    if (checkpoint) {
      std::ostringstream engine;
      engine << rng;
      checkpoint({first_new, best_per_n, beam, engine.str()});
    }
  }
  return best_per_n;
}

}  // namespace bricklayer::planner
