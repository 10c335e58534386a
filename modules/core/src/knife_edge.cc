// Stable / falls / knife edge from the blocks' position uncertainty (modules/core/README.md "Knife edges").
//
// Stable is proved by forces that survive every placement (a robust version of Paterson & Zwick's LP: contact
// forces whose points of action may move with the blocks, with a budget for how far the moments must be
// re-distributed); falls is proved by a falling mechanism that stays a Farkas certificate of imbalance for
// every placement. Both certificates are sufficient, never necessary: what neither proves is a knife edge.
#include "bricklayer/core/knife_edge.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bricklayer/core/contacts.h"
#include "bricklayer/core/dynamics.h"
#include "bricklayer/core/program.h"

namespace bricklayer::core {
namespace {

// Below this a contact force is taken as zero (the statics' forces are exact to roundoff).
constexpr double kNoForce = 1e-12;

// A pair of blocks (or a block and the surface) that touch, or may touch once the blocks move.
struct Pair {
  int upper = 0;
  int lower = kSurface;
  double lo = 0.0;  // measured contact interval; lo > hi for a gap (a contact that may appear)
  double hi = 0.0;
};

// Existing contacts plus every pair of adjacent-row blocks (and row-0 block and surface) whose gap is below
// `gap`: a falling mechanism must not push through a block it may touch.
std::vector<Pair> pairs_within(const ContactGraph& g, const std::vector<double>& u, double uniform_gap) {
  std::vector<Pair> out;
  out.reserve(g.contacts.size() + 8);
  for (const Contact& c : g.contacts) out.push_back({c.upper, c.lower, c.left, c.right});
  auto gap_limit = [&](int a, int b) {
    if (uniform_gap >= 0.0) return uniform_gap;
    return u[static_cast<size_t>(a)] + (b == kSurface ? 0.0 : u[static_cast<size_t>(b)]);
  };
  for (int i : g.rows.empty() ? std::vector<int>{} : g.rows[0]) {
    const double lo = g.x[static_cast<size_t>(i)];
    const double hi = std::min(lo + 1.0, 0.0);
    if (hi - lo <= kContactTolerance && lo - hi < gap_limit(i, kSurface)) out.push_back({i, kSurface, lo, hi});
  }
  for (int r = 1; r < g.num_rows(); ++r) {
    for (int i : g.rows[static_cast<size_t>(r)]) {
      const double xi = g.x[static_cast<size_t>(i)];
      for (int j : g.rows[static_cast<size_t>(r - 1)]) {
        const double xj = g.x[static_cast<size_t>(j)];
        const double lo = std::max(xi, xj);
        const double hi = std::min(xi, xj) + 1.0;
        if (hi - lo <= kContactTolerance && lo - hi < gap_limit(i, j)) out.push_back({i, j, lo, hi});
      }
    }
  }
  return out;
}

// Which block an end of a pair's interval belongs to, so how far it can move: the left end is the left end of
// the right-hand block, the right end the right end of the left-hand block; the surface edge never moves.
// Returns the block index, or kSurface for the edge (ties: the one with the larger uncertainty, via `u`).
int end_owner(const ContactGraph& g, int upper, int lower, int end, const std::vector<double>* u = nullptr) {
  const double xu = g.x[static_cast<size_t>(upper)];
  if (lower == kSurface) return end == 0 ? upper : (xu + 1.0 < 0.0 ? upper : kSurface);
  const double xl = g.x[static_cast<size_t>(lower)];
  if (xu == xl) {
    return (u != nullptr && (*u)[static_cast<size_t>(lower)] > (*u)[static_cast<size_t>(upper)]) ? lower : upper;
  }
  if (end == 0) return xu > xl ? upper : lower;
  return xu < xl ? upper : lower;
}

// How far an end of the pair's interval may move: the owner's uncertainty (per block), 0 for the edge.
double end_shift(const ContactGraph& g, int upper, int lower, int end, const std::vector<double>& u) {
  const int owner = end_owner(g, upper, lower, end, &u);
  return owner == kSurface ? 0.0 : u[static_cast<size_t>(owner)];
}

// Optimal -> the result; infeasible -> nullopt-like (status kept); anything else is a backend failure.
bool solve(const opt::Problem& problem, const std::string& solver, const char* what, opt::SolveResult& result) {
  opt::SolverOptions options;
  options.feasibility_tolerance = solver == "nlopt" ? 1e-6 : 1e-9;
  result = opt::make_solver(solver)->solve(problem, options);
  if (result.status == opt::SolveStatus::kOptimal) return true;
  if (result.status == opt::SolveStatus::kInfeasible) return false;
  throw SolverError(std::string(what) + " LP (" + solver + "): " + opt::to_string(result.status) + ": " +
                    result.message);
}

// Bounds of every LP variable (CLP's dual simplex reports free columns without a starting basis as
// infeasible, so none is free): no contact carries more than the whole pile, at no point further out than
// the furthest block end; velocities of a mechanism normalised to unit work stay within `kVelocityBound`.
double moment_bound(const ContactGraph& g) {
  double far = 1.0;
  for (double x : g.x) far = std::max(far, std::abs(x) + 1.0);
  return static_cast<double>(g.size()) * far + 1.0;
}
constexpr double kVelocityBound = 1e6;

// Variables of the statics LPs: per contact k, its total force F (optional), its moment m about the origin
// (sum of force x position) and its budget B >= 0 (how far m may have to change when the blocks move).
struct StaticsVars {
  std::vector<int> force, moment, budget;
};

// Rows shared by both statics LPs: each block's moment equation and its budget row.
//   sum_sup m - sum_carr m = c_i            (with the fixed or variable forces, the block's moment balance)
//   sum_sup B - sum_carr B >= own_shift_i   (its own move d_i plus every move passed down from above can be
//                                            taken up by moving its support forces' points of action)
// own_shift: a constant per block (u_i), or, when delta >= 0, that variable (uniform uncertainty).
void add_block_rows(const ContactGraph& g, opt::Problem& p, const StaticsVars& v, const std::vector<double>* own,
                    int delta) {
  for (size_t i = 0; i < g.size(); ++i) {
    const int moment_row = p.add_row(g.centre(static_cast<int>(i)), g.centre(static_cast<int>(i)));
    const int budget_row = p.add_row(own ? (*own)[i] : 0.0, opt::kInfinity);
    for (int k : g.supports[i]) {
      p.set(moment_row, v.moment[static_cast<size_t>(k)], 1.0);
      p.set(budget_row, v.budget[static_cast<size_t>(k)], 1.0);
    }
    for (int k : g.carries[i]) {
      p.set(moment_row, v.moment[static_cast<size_t>(k)], -1.0);
      p.set(budget_row, v.budget[static_cast<size_t>(k)], -1.0);
    }
    if (delta >= 0) p.set(budget_row, delta, -1.0);
  }
}

// The stable margin, O(n): the stability LP's certificate (totals F, moments m, budgets B = delta b) built
// greedily top-down for a uniform delta instead of optimised. Each block puts its load (its weight plus what
// it carries, at its centre of pressure) either on one support, at the centre of pressure, or on two supports
// at their midpoints by the lever rule, whichever of these choices lets its own contacts take the largest
// delta; its budget (1 + what it carries) is split between the two in proportion to the forces, or (second
// variant, split_by_room) by the room each has left at the block's own best delta. Returns the largest uniform
// delta this certificate proves (-1: none).
double stable_margin_greedy(const ContactGraph& g, bool split_by_room, int* limiting = nullptr) {
  const size_t k_count = g.contacts.size();
  std::vector<double> force(k_count, 0.0), moment(k_count, 0.0), budget(k_count, 0.0);
  std::vector<double> lo_moves(k_count), hi_moves(k_count);
  for (size_t k = 0; k < k_count; ++k) {
    const Contact& c = g.contacts[k];
    lo_moves[k] = end_owner(g, c.upper, c.lower, 0) == kSurface ? 0.0 : 1.0;
    hi_moves[k] = end_owner(g, c.upper, c.lower, 1) == kSurface ? 0.0 : 1.0;
  }
  // What contact k allows with force f at point p and budget b.
  auto allows = [&](size_t k, double f, double p, double b) {
    const Contact& c = g.contacts[k];
    return std::min(f * (p - c.left) / (b + f * lo_moves[k]), f * (c.right - p) / (b + f * hi_moves[k]));
  };
  // How much budget contact k (force f at p) can take at a move delta while keeping its point inside.
  auto room = [&](size_t k, double f, double p, double delta) {
    const Contact& c = g.contacts[k];
    return f * std::min((p - c.left) / delta - lo_moves[k], (c.right - p) / delta - hi_moves[k]);
  };
  // Two supports: the largest delta for which their room covers the budget `need` (split by room, not by
  // force, so a long contact takes the budget a hair-thin one cannot). Bisection; the room shrinks with delta.
  auto pair_delta = [&](size_t ka, double fa, double pa, size_t kb, double fb, double pb, double need, double& share_a) {
    auto fits = [&](double delta) {
      const double ra = fa > 0.0 ? room(ka, fa, pa, delta) : 0.0;
      const double rb = fb > 0.0 ? room(kb, fb, pb, delta) : 0.0;
      return ra >= 0.0 && rb >= 0.0 && ra + rb >= need;
    };
    double lo = 0.0, hi = kMaxMargin;
    if (fits(hi)) {
      lo = hi;
    } else {
      for (int it = 0; it < 40; ++it) {
        const double mid = 0.5 * (lo + hi);
        (fits(mid) ? lo : hi) = mid;
      }
    }
    if (!(lo > 0.0)) return -1.0;
    const double ra = fa > 0.0 ? room(ka, fa, pa, lo) : 0.0;
    const double rb = fb > 0.0 ? room(kb, fb, pb, lo) : 0.0;
    share_a = ra + rb > 0.0 ? ra / (ra + rb) : 0.5;
    return lo;
  };
  double margin = kMaxMargin;
  for (int r = g.num_rows() - 1; r >= 0 && margin > 0.0; --r) {
    for (int i : g.rows[static_cast<size_t>(r)]) {
      const auto& sup = g.supports[static_cast<size_t>(i)];
      if (sup.empty()) return -1.0;
      double load = 1.0;
      double torque = g.centre(i);
      double need = 1.0;
      for (int k : g.carries[static_cast<size_t>(i)]) {
        load += force[static_cast<size_t>(k)];
        torque += moment[static_cast<size_t>(k)];
        need += budget[static_cast<size_t>(k)];
      }
      const double pressure = torque / load;
      double best = -1.0;
      size_t ba = k_count, bb = k_count;
      double fa = 0.0;
      double share = 1.0;
      for (size_t x = 0; x < sup.size(); ++x) {
        const size_t ka = static_cast<size_t>(sup[x]);
        const double one = allows(ka, load, pressure, need);
        if (one > best) {
          best = one;
          ba = ka;
          bb = k_count;
          fa = load;
        }
        const double ma = 0.5 * (g.contacts[ka].left + g.contacts[ka].right);
        for (size_t y = x + 1; y < sup.size(); ++y) {
          const size_t kb = static_cast<size_t>(sup[y]);
          const double mb = 0.5 * (g.contacts[kb].left + g.contacts[kb].right);
          if (!(mb - ma > kContactTolerance) || pressure < ma || pressure > mb) continue;
          const double f1 = load * (mb - pressure) / (mb - ma);
          const double f2 = load - f1;
          double share_a = f1 / load;
          const double both =
              split_by_room ? pair_delta(ka, f1, ma, kb, f2, mb, need, share_a)
                            : std::min(f1 > 0.0 ? allows(ka, f1, ma, need * f1 / load) : kMaxMargin,
                                       f2 > 0.0 ? allows(kb, f2, mb, need * f2 / load) : kMaxMargin);
          if (both > best) {
            best = both;
            ba = ka;
            bb = kb;
            fa = f1;
            share = share_a;
          }
        }
      }
      if (limiting != nullptr && best < margin) *limiting = i;
      if (!(best > 0.0)) return -1.0;
      margin = std::min(margin, best);
      if (bb == k_count) {
        force[ba] = load;
        moment[ba] = torque;
        budget[ba] = need;
        continue;
      }
      const double ma = 0.5 * (g.contacts[ba].left + g.contacts[ba].right);
      const double mb = 0.5 * (g.contacts[bb].left + g.contacts[bb].right);
      force[ba] = fa;
      force[bb] = load - fa;
      moment[ba] = fa * ma;
      moment[bb] = (load - fa) * mb;
      budget[ba] = need * share;
      budget[bb] = need * (1.0 - share);
    }
  }
  return margin > 0.0 ? margin : -1.0;
}

// A witness against a certain verdict, without an LP: the pile sheared at a row (every block of that row and
// above moved by +-u_i, every block below by -+u_i, both ways). Returns true when one of the two placements
// is valid and its exact verdict is `balanced` -- then the pile is a knife edge for sure.
bool sheared_placement_is(const Stack& stack, const ContactGraph& g, int row, const std::vector<double>& u,
                          const PredictOptions& options, bool balanced) {
  for (double s : {1.0, -1.0}) {
    Stack t = stack;
    for (size_t i = 0; i < t.blocks.size(); ++i) {
      t.blocks[i].x += (g.row[i] >= row ? s : -s) * u[i] * stack.block_length;
    }
    try {
      if (predict(t, options).balanced == balanced) return true;
    } catch (const StackError&) {  // the shear pushed two blocks of a row into each other: no placement
    }
  }
  return false;
}

// Whether every placement with block i within u_i of its measured x is balanced, with the contact forces
// free (the same LP with F variable and the uncertainty fixed). On success, the totals per contact.
bool stable_for(const ContactGraph& g, const std::vector<double>& u, const std::string& solver,
                std::vector<double>& contact_force, int& lps) {
  opt::Problem p;
  StaticsVars v;
  const size_t k_count = g.contacts.size();
  v.force.resize(k_count);
  v.moment.resize(k_count);
  v.budget.resize(k_count);
  const double bound = moment_bound(g);
  for (size_t k = 0; k < k_count; ++k) {
    v.force[k] = p.add_variable(0.0, static_cast<double>(g.size()), 0.0);
    v.moment[k] = p.add_variable(-bound, bound, 0.0);
    v.budget[k] = p.add_variable(0.0, opt::kInfinity, 0.0);
  }
  add_block_rows(g, p, v, &u, -1);
  for (size_t i = 0; i < g.size(); ++i) {
    const int force_row = p.add_row(1.0, 1.0);
    for (int k : g.supports[i]) p.set(force_row, v.force[static_cast<size_t>(k)], 1.0);
    for (int k : g.carries[i]) p.set(force_row, v.force[static_cast<size_t>(k)], -1.0);
  }
  for (size_t k = 0; k < k_count; ++k) {
    const Contact& c = g.contacts[k];
    // Each end of the interval moves with the block it belongs to (the surface edge does not move).
    const double el = end_shift(g, c.upper, c.lower, 0, u);
    const double er = end_shift(g, c.upper, c.lower, 1, u);
    const int left = p.add_row(0.0, opt::kInfinity);
    p.set(left, v.moment[k], 1.0);
    p.set(left, v.budget[k], -1.0);
    p.set(left, v.force[k], -(c.left + el));
    const int right = p.add_row(0.0, opt::kInfinity);
    p.set(right, v.moment[k], -1.0);
    p.set(right, v.budget[k], -1.0);
    p.set(right, v.force[k], c.right - er);
  }
  ++lps;
  opt::SolveResult r;
  if (!solve(p, solver, "knife edge (stable)", r)) return false;
  contact_force.assign(k_count, 0.0);
  for (size_t k = 0; k < k_count; ++k) contact_force[k] = std::max(0.0, r.x[static_cast<size_t>(v.force[k])]);
  return true;
}

// The largest uniform uncertainty delta for which the measured pile's falling motion (its rotations alpha
// fixed, vertical velocities v free) stays a falling mechanism for every placement: at every end of every
// pair that touches or may touch, in the contact interval widened by delta and with both centres moved by
// delta, the upper block does not move down into the lower one, and the blocks' centres go down on the whole
// (a Farkas certificate that no contact forces balance the pile). -1 when even delta = 0 fails.
double falls_margin(const ContactGraph& g, const std::vector<double>& accel, const std::vector<double>& alpha,
                    const std::string& solver, int& lps) {
  double work = 0.0;
  for (double a : accel) work -= a;
  if (!(work > 0.0)) return -1.0;
  opt::Problem p;
  std::vector<int> v(g.size());
  double scale = work;
  for (size_t i = 0; i < g.size(); ++i) scale += std::abs(accel[i]) + std::abs(alpha[i]);
  const double v_bound = kVelocityBound * scale * moment_bound(g);
  for (size_t i = 0; i < g.size(); ++i) v[i] = p.add_variable(-v_bound, v_bound, 0.0);
  const int delta = p.add_variable(0.0, kMaxMargin, -1.0);
  const std::vector<Pair> pairs = pairs_within(g, {}, 2.0 * kMaxMargin);
  for (const Pair& pr : pairs) {
    const double wu = alpha[static_cast<size_t>(pr.upper)];
    const double wl = pr.lower == kSurface ? 0.0 : alpha[static_cast<size_t>(pr.lower)];
    const double cu = g.centre(pr.upper);
    const double cl = pr.lower == kSurface ? 0.0 : g.centre(pr.lower);
    for (int end = 0; end < 2; ++end) {
      const double p0 = end == 0 ? pr.lo : pr.hi;
      // The end moves outward, p = p0 + s delta, unless it is the surface edge.
      const double s = end_owner(g, pr.upper, pr.lower, end) == kSurface ? 0.0 : (end == 0 ? -1.0 : 1.0);
      const double constant = wu * (p0 - cu) - wl * (p0 - cl);
      const double per_delta = s * (wu - wl) - std::abs(wu) - std::abs(wl);
      const int row = p.add_row(-constant, opt::kInfinity);
      p.set(row, v[static_cast<size_t>(pr.upper)], 1.0);
      if (pr.lower != kSurface) p.set(row, v[static_cast<size_t>(pr.lower)], -1.0);
      p.set(row, delta, per_delta);
    }
  }
  // The measured motion does work `work`; ask for a ten-thousandth of it so the certificate is not a sliver.
  const int work_row = p.add_row(1e-4 * work, opt::kInfinity);
  for (size_t i = 0; i < g.size(); ++i) p.set(work_row, v[i], -1.0);
  ++lps;
  // The falls margin only refines a lower bound: a backend that stops at its iteration limit (large
  // measured piles of touching blocks) leaves the bound the cut gave, never the whole verdict failed.
  opt::SolverOptions options;
  options.feasibility_tolerance = solver == "nlopt" ? 1e-6 : 1e-9;
  const opt::SolveResult r = opt::make_solver(solver)->solve(p, options);
  if (r.status != opt::SolveStatus::kOptimal) return -1.0;
  return std::clamp(r.x[static_cast<size_t>(delta)], 0.0, kMaxMargin);
}

// Whether some falling mechanism (rotations free too) is a certificate of imbalance for every placement with
// block i within u_i: the same rows with the per-block uncertainties, |omega| through A_i >= +-omega_i.
bool falls_for(const ContactGraph& g, const std::vector<double>& u, const std::string& solver, int& lps) {
  opt::Problem p;
  std::vector<int> v(g.size()), w(g.size()), a(g.size());
  for (size_t i = 0; i < g.size(); ++i) {
    v[i] = p.add_variable(-kVelocityBound, kVelocityBound, 0.0);
    w[i] = p.add_variable(-kVelocityBound, kVelocityBound, 0.0);
    a[i] = p.add_variable(0.0, kVelocityBound, 0.0);
    const int plus = p.add_row(0.0, opt::kInfinity);
    p.set(plus, a[i], 1.0);
    p.set(plus, w[i], -1.0);
    const int minus = p.add_row(0.0, opt::kInfinity);
    p.set(minus, a[i], 1.0);
    p.set(minus, w[i], 1.0);
  }
  const std::vector<Pair> pairs = pairs_within(g, u, -1.0);
  for (const Pair& pr : pairs) {
    const double uu = u[static_cast<size_t>(pr.upper)];
    const double ul = pr.lower == kSurface ? 0.0 : u[static_cast<size_t>(pr.lower)];
    const double cu = g.centre(pr.upper);
    const double cl = pr.lower == kSurface ? 0.0 : g.centre(pr.lower);
    for (int end = 0; end < 2; ++end) {
      const double e = end_shift(g, pr.upper, pr.lower, end, u);
      const double pt = end == 0 ? pr.lo - e : pr.hi + e;
      const int row = p.add_row(0.0, opt::kInfinity);
      p.set(row, v[static_cast<size_t>(pr.upper)], 1.0);
      p.set(row, w[static_cast<size_t>(pr.upper)], pt - cu);
      p.set(row, a[static_cast<size_t>(pr.upper)], -uu);
      if (pr.lower != kSurface) {
        p.set(row, v[static_cast<size_t>(pr.lower)], -1.0);
        p.set(row, w[static_cast<size_t>(pr.lower)], -(pt - cl));
        p.set(row, a[static_cast<size_t>(pr.lower)], -ul);
      }
    }
  }
  const int work_row = p.add_row(1.0, opt::kInfinity);
  for (size_t i = 0; i < g.size(); ++i) p.set(work_row, v[i], -1.0);
  ++lps;
  opt::SolveResult r;
  return solve(p, solver, "knife edge (falls)", r);
}

// Falls proved by a cut: a set S of blocks closed upwards (every block that rests, or may come to rest, on a
// member is a member) is carried only from below, through the pairs from a member to a non-member. Internal
// forces cancel, so S balances only if its centre of mass lies within the hull of those pairs' intervals,
// whatever the placement inside S. For S = each block with everything above it, and S = the whole pile:
// uniform = the largest uniform move for which some S's centre stays outside its hull (its centre moves by
// at most delta, each hull end by delta unless it is the surface edge); proved_for_u = the same with the
// per-block uncertainties (the centre moves by at most the members' mean u).
struct CutResult {
  double uniform = -1.0;
  bool proved_for_u = false;
};
CutResult falls_by_cut(const ContactGraph& g, const std::vector<Pair>& pairs, const std::vector<double>& u) {
  CutResult out;
  const size_t n = g.size();
  std::vector<std::vector<int>> above(n);  // pair indices where the block is the lower one
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (pairs[k].lower != kSurface) above[static_cast<size_t>(pairs[k].lower)].push_back(static_cast<int>(k));
  }
  std::vector<char> member(n, 0);
  std::vector<int> stack;
  auto test = [&](int seed) {
    std::fill(member.begin(), member.end(), 0);
    double centre = 0.0;
    double mean_u = 0.0;
    int count = 0;
    stack.clear();
    if (seed >= 0) {
      stack.push_back(seed);
      member[static_cast<size_t>(seed)] = 1;
    } else {
      for (size_t i = 0; i < n; ++i) {
        member[i] = 1;
        stack.push_back(static_cast<int>(i));
      }
    }
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      centre += g.centre(i);
      mean_u += u[static_cast<size_t>(i)];
      ++count;
      for (int k : above[static_cast<size_t>(i)]) {
        const int j = pairs[static_cast<size_t>(k)].upper;
        if (!member[static_cast<size_t>(j)]) {
          member[static_cast<size_t>(j)] = 1;
          stack.push_back(j);
        }
      }
    }
    centre /= count;
    mean_u /= count;
    double right_margin = kMaxMargin, left_margin = kMaxMargin;  // no boundary at all: it rests on nothing
    bool right_u = true, left_u = true;
    for (const Pair& pr : pairs) {
      if (!member[static_cast<size_t>(pr.upper)] || (pr.lower != kSurface && member[static_cast<size_t>(pr.lower)])) continue;
      const bool right_moves = end_owner(g, pr.upper, pr.lower, 1) != kSurface;
      const bool left_moves = end_owner(g, pr.upper, pr.lower, 0) != kSurface;
      right_margin = std::min(right_margin, (centre - pr.hi) / (right_moves ? 2.0 : 1.0));
      left_margin = std::min(left_margin, (pr.lo - centre) / (left_moves ? 2.0 : 1.0));
      right_u = right_u && centre - mean_u > pr.hi + end_shift(g, pr.upper, pr.lower, 1, u);
      left_u = left_u && centre + mean_u < pr.lo - end_shift(g, pr.upper, pr.lower, 0, u);
    }
    out.uniform = std::max(out.uniform, std::max(right_margin, left_margin));
    out.proved_for_u = out.proved_for_u || right_u || left_u;
  };
  test(-1);
  for (size_t i = 0; i < n; ++i) test(static_cast<int>(i));
  out.uniform = std::min(out.uniform, kMaxMargin);
  return out;
}

// The measured contact graph with every contact interval shortened by s at both ends (shorter ones dropped).
ContactGraph narrowed(const ContactGraph& g, double s) {
  ContactGraph out = g;
  out.contacts.clear();
  for (auto& v : out.supports) v.clear();
  for (auto& v : out.carries) v.clear();
  for (const Contact& c : g.contacts) {
    if (c.right - c.left - 2.0 * s <= kContactTolerance) continue;
    const int index = static_cast<int>(out.contacts.size());
    out.contacts.push_back({c.upper, c.lower, c.left + s, c.right - s});
    out.supports[static_cast<size_t>(c.upper)].push_back(index);
    if (c.lower != kSurface) out.carries[static_cast<size_t>(c.lower)].push_back(index);
  }
  return out;
}

// The blocks that would be the causes if a measured-balanced knife-edge pile fell: the exact annotator's
// causes on the graph with every contact narrowed by twice the uncertainty (the relative move of two
// blocks), doubled until some block is a cause.
std::vector<int64_t> deciding_if_it_falls(const Stack& stack, const ContactGraph& g, double u, QpMethod qp) {
  for (double s = std::max(2.0 * u, 1e-3); s <= 4.0 * kMaxMargin; s *= 2.0) {
    const std::vector<BlockState> states = exact_states(narrowed(g, s), qp);
    std::vector<int64_t> ids;
    for (size_t i = 0; i < states.size(); ++i) {
      if (states[i] == BlockState::kCause) ids.push_back(stack.blocks[i].id);
    }
    if (!ids.empty()) return ids;
  }
  return {};
}

}  // namespace

const char* to_string(Certainty certainty) {
  switch (certainty) {
    case Certainty::kStable: return "stable";
    case Certainty::kFalls: return "falls";
    case Certainty::kKnifeEdge: return "knife edge";
  }
  return "knife edge";
}

KnifeEdgeVerdict judge_knife_edge(const Stack& stack, const std::vector<double>& uncertainty,
                                  const PredictOptions& options, size_t max_lp_blocks) {
  if (options.position_tolerance != 0.0) {
    throw std::invalid_argument("judge_knife_edge: the position uncertainty replaces position_tolerance (set it to 0)");
  }
  if (uncertainty.size() != stack.blocks.size()) {
    throw std::invalid_argument("judge_knife_edge: " + std::to_string(uncertainty.size()) + " uncertainties for " +
                                std::to_string(stack.blocks.size()) + " blocks");
  }
  KnifeEdgeVerdict out;
  for (size_t i = 0; i < uncertainty.size(); ++i) {
    if (!(uncertainty[i] >= 0.0 && uncertainty[i] <= kMaxUncertainty)) {
      throw std::invalid_argument("block " + std::to_string(i) + ": position uncertainty " +
                                  std::to_string(uncertainty[i]) + " is outside [0, " +
                                  std::to_string(kMaxUncertainty) + "] block lengths");
    }
    out.uncertainty = std::max(out.uncertainty, uncertainty[i]);
  }
  out.nominal = predict(stack, options);  // validates
  const ContactGraph g = build_contacts(stack);
  const std::string& solver = options.solver;
  const bool lps = g.size() <= max_lp_blocks;
  if (g.size() == 0) {
    out.margin = kMaxMargin;
    return out;
  }
  if (out.nominal.balanced) {
    // Two greedy variants (budgets split by force, or by the room each contact has); the better one counts.
    int limiting = -1, limiting_room = -1;
    double quick = stable_margin_greedy(g, false, &limiting);
    if (quick < out.uncertainty) {
      const double by_room = stable_margin_greedy(g, true, &limiting_room);
      if (by_room > quick) {
        quick = by_room;
        limiting = limiting_room;
      }
    }
    if (quick >= out.uncertainty && quick >= 0.0) {
      out.certainty = Certainty::kStable;
      out.margin = quick;
      return out;
    }
    // A placement that falls, sheared where the greedy certificate is tightest, settles it without an LP.
    if (limiting >= 0 && sheared_placement_is(stack, g, g.row[static_cast<size_t>(limiting)], uncertainty, options, false)) {
      out.certainty = Certainty::kKnifeEdge;
      out.margin = std::max(0.0, quick);
      out.deciding = deciding_if_it_falls(stack, g, out.uncertainty, options.qp);
      return out;
    }
    // One LP: the forces re-chosen for the per-block uncertainties. Its margin is at least u; the greedy's
    // may be larger.
    std::vector<double> robust;
    if (lps && stable_for(g, uncertainty, solver, robust, out.linear_programs)) {
      out.certainty = Certainty::kStable;
      out.margin = std::max(out.uncertainty, quick);
      return out;
    }
    const double margin = quick;
    out.certainty = Certainty::kKnifeEdge;
    out.margin = std::max(0.0, margin);
    out.deciding = deciding_if_it_falls(stack, g, out.uncertainty, options.qp);
    return out;
  }
  out.deciding = out.nominal.causes();
  std::vector<double> accel(g.size()), alpha(g.size());
  if (!out.nominal.qp.empty()) {
    for (size_t i = 0; i < g.size(); ++i) {
      accel[i] = out.nominal.blocks[i].accel;
      alpha[i] = out.nominal.blocks[i].alpha;
    }
  } else {  // paper / balance annotators compute no motion; the physics' one is the mechanism to test
    const Accelerations z = initial_accelerations(g, {}, options.qp);
    accel = z.a;
    alpha = z.alpha;
  }
  const CutResult cut = falls_by_cut(g, pairs_within(g, {}, 2.0 * kMaxMargin), uncertainty);
  if (cut.proved_for_u) {
    out.certainty = Certainty::kFalls;
    out.margin = -std::max(out.uncertainty, cut.uniform);
    return out;
  }
  // A placement that stands, sheared at the lowest row of causes, settles it without an LP.
  int cause_row = g.num_rows();
  for (size_t i = 0; i < g.size(); ++i) {
    if (out.nominal.blocks[i].state == BlockState::kCause) cause_row = std::min(cause_row, g.row[i]);
  }
  if (cause_row < g.num_rows() && sheared_placement_is(stack, g, cause_row, uncertainty, options, true)) {
    out.certainty = Certainty::kKnifeEdge;
    out.margin = -std::max(0.0, cut.uniform);
    return out;
  }
  const double margin = std::max(cut.uniform, lps ? falls_margin(g, accel, alpha, solver, out.linear_programs) : -1.0);
  if (margin >= out.uncertainty && margin >= 0.0) {
    out.certainty = Certainty::kFalls;
    out.margin = -margin;
    return out;
  }
  if (lps && falls_for(g, uncertainty, solver, out.linear_programs)) {
    out.certainty = Certainty::kFalls;
    out.margin = -std::max(out.uncertainty, margin);
    return out;
  }
  out.certainty = Certainty::kKnifeEdge;
  out.margin = -std::max(0.0, margin);
  return out;
}

}  // namespace bricklayer::core
