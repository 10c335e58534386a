#include "bricklayer/study/placement.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include "bricklayer/core/contacts.h"
#include "bricklayer/core/predict.h"
#include "bricklayer/core/program.h"

namespace bricklayer::study {
namespace {

// Samples of the one-block proof sit this far inside a cell, so that the contact geometry there is the
// cell's (contacts need an overlap above core::kContactTolerance = 1e-9); the Lipschitz bound covers the
// remaining sliver up to the cell's end.
constexpr double kInset = 1e-8;

std::vector<double> row_positions(const core::Stack& pile, int32_t row) {
  std::vector<double> xs;
  for (const auto& b : pile.blocks) {
    if (b.row == row) xs.push_back(b.x);
  }
  std::sort(xs.begin(), xs.end());
  return xs;
}

// Union of open intervals given as closed [lo, hi] (sorted, merged).
std::vector<Range> merged(std::vector<Range> ranges) {
  std::sort(ranges.begin(), ranges.end(), [](const Range& a, const Range& b) { return a.lo < b.lo; });
  std::vector<Range> out;
  for (const Range& r : ranges) {
    if (!out.empty() && r.lo <= out.back().hi) {
      out.back().hi = std::max(out.back().hi, r.hi);
    } else {
      out.push_back(r);
    }
  }
  return out;
}

std::vector<Range> intersect(const std::vector<Range>& a, const std::vector<Range>& b) {
  std::vector<Range> out;
  for (const Range& p : a) {
    for (const Range& q : b) {
      const double lo = std::max(p.lo, q.lo);
      const double hi = std::min(p.hi, q.hi);
      if (lo <= hi) out.push_back({lo, hi});
    }
  }
  std::sort(out.begin(), out.end(), [](const Range& x, const Range& y) { return x.lo < y.lo; });
  return out;
}

core::PredictOptions exact_options(double position_tolerance) {
  core::PredictOptions o;
  o.annotator = core::Annotator::kExact;
  o.position_tolerance = position_tolerance;
  return o;
}

// Positions on a grid inside every cell of the critical positions of every range of `row`.
std::vector<double> grid_candidates(const core::Stack& pile, int32_t row, double step, bool or_carrying) {
  std::vector<double> xs;
  for (const Range& range : placement_ranges(pile, row, or_carrying)) {
    if (range.hi - range.lo <= 0) {
      xs.push_back(range.lo);
      continue;
    }
    const std::vector<double> cuts = critical_positions(pile, row, range);
    for (size_t c = 0; c + 1 < cuts.size(); ++c) {
      const double a = cuts[c];
      const double b = cuts[c + 1];
      const int m = std::max(1, static_cast<int>(std::ceil((b - a) / step)));
      for (int i = 0; i < m; ++i) xs.push_back(a + (b - a) * (i + 0.5) / m);
    }
  }
  return xs;
}

// The certified one-block search of the file comment of placement.h.
class OneBlockSearch {
 public:
  OneBlockSearch(const core::Stack& pile, const SearchOptions& options)
      : pile_(pile), options_(options), lipschitz_(2.0 * static_cast<double>(pile.blocks.size() + 1)) {}

  // Returns true when a witness was found.
  bool run() {
    for (int32_t row = 0; row <= highest_useful_row(pile_) && !witness_; ++row) {
      for (const Range& range : placement_ranges(pile_, row)) {
        if (witness_) break;
        if (range.hi - range.lo <= 2 * kInset) {
          point(row, 0.5 * (range.lo + range.hi), range.hi - range.lo);
          continue;
        }
        const std::vector<double> cuts = critical_positions(pile_, row, range);
        for (size_t c = 0; c + 1 < cuts.size() && !witness_; ++c) cell(row, cuts[c], cuts[c + 1]);
      }
    }
    return witness_.has_value();
  }

  std::optional<Placement> witness_;
  size_t lp_evaluations_ = 0;
  size_t predictions_ = 0;
  size_t undecided_ = 0;

 private:
  double violation(int32_t row, double x) {
    ++lp_evaluations_;
    return bounded_violation(pile_, {row, x}, options_.position_tolerance);
  }

  // A sample with V <= tolerance: ask the exact annotator (the judge).
  bool try_witness(int32_t row, double x, double v) {
    if (v > core::kBalanceTolerance) return false;
    ++predictions_;
    if (!stands(with_added(pile_, {{row, x}}), options_.position_tolerance)) return false;
    witness_ = Placement{row, x};
    return true;
  }

  // A range too narrow to hold two inset samples (a gap one block wide, up to rounding).
  void point(int32_t row, double x, double width) {
    const double v = violation(row, x);
    if (try_witness(row, x, v)) return;
    if (v - lipschitz_ * width > core::kBalanceTolerance) return;
    ++undecided_;
  }

  void cell(int32_t row, double a, double b) {
    if (b - a <= 2 * kInset) {
      point(row, 0.5 * (a + b), b - a);
      return;
    }
    const double lo = a + kInset;
    const double hi = b - kInset;
    const double vlo = violation(row, lo);
    if (try_witness(row, lo, vlo)) return;
    const double vhi = violation(row, hi);
    if (try_witness(row, hi, vhi)) return;
    // The slivers [a, lo] and [hi, b]: contacts there are a subset of the cell's (at the very end a contact
    // may have vanished, which only raises V), so the bound from the inset sample holds.
    if (vlo - lipschitz_ * kInset <= core::kBalanceTolerance) ++undecided_;
    if (vhi - lipschitz_ * kInset <= core::kBalanceTolerance) ++undecided_;
    refine(row, lo, hi, vlo, vhi);
  }

  void refine(int32_t row, double lo, double hi, double vlo, double vhi) {
    if (witness_) return;
    // V is L-Lipschitz on [lo, hi]: its minimum there is at least (V(lo) + V(hi) - L (hi - lo)) / 2.
    if (0.5 * (vlo + vhi - lipschitz_ * (hi - lo)) > core::kBalanceTolerance) return;
    if (hi - lo < options_.min_interval) {
      ++undecided_;
      return;
    }
    const double mid = 0.5 * (lo + hi);
    const double vmid = violation(row, mid);
    if (try_witness(row, mid, vmid)) return;
    refine(row, lo, mid, vlo, vmid);
    refine(row, mid, hi, vmid, vhi);
  }

  const core::Stack& pile_;
  const SearchOptions& options_;
  const double lipschitz_;
};

// Witness search for `remaining` more blocks on `pile` (grid candidates, recomputed after each block).
bool grid_search(const core::Stack& pile, int remaining, const SearchOptions& options, std::vector<Placement>& chosen,
                 size_t& evaluations) {
  const core::Stack current = with_added(pile, chosen);
  for (int32_t row = 0; row <= highest_useful_row(current); ++row) {
    for (double x : grid_candidates(current, row, options.pair_step, remaining > 1)) {
      if (evaluations >= options.max_evaluations) return false;
      chosen.push_back({row, x});
      if (remaining == 1) {
        ++evaluations;
        if (stands(with_added(pile, chosen), options.position_tolerance)) return true;
      } else if (grid_search(pile, remaining - 1, options, chosen, evaluations)) {
        return true;
      }
      chosen.pop_back();
    }
  }
  return false;
}

}  // namespace

core::Stack normalised(const core::Stack& pile) {
  core::Stack out = pile;
  out.block_length = 1.0;
  out.block_height = pile.block_height / pile.block_length;
  out.table_edge = 0.0;
  for (auto& b : out.blocks) b.x = (b.x - pile.table_edge) / pile.block_length;
  return out;
}

core::Stack with_added(const core::Stack& pile, const std::vector<Placement>& added) {
  core::Stack out = pile;
  int64_t next = 0;
  for (const auto& b : pile.blocks) next = std::max(next, b.id + 1);
  for (const Placement& p : added) out.blocks.push_back({next++, p.row, p.x});
  return out;
}

bool stands(const core::Stack& pile, double position_tolerance) {
  return core::predict(pile, exact_options(position_tolerance)).balanced;
}

int32_t highest_useful_row(const core::Stack& pile) {
  int32_t top = -1;
  for (const auto& b : pile.blocks) top = std::max(top, b.row);
  return top + 1;
}

std::vector<Range> placement_ranges(const core::Stack& pile, int32_t row, bool or_carrying) {
  constexpr double kFar = 1e9;
  // Where the block overlaps no block of its row (touching allowed).
  std::vector<Range> free;
  double lo = -kFar;
  for (double x : row_positions(pile, row)) {
    if (x - 1.0 >= lo) free.push_back({lo, x - 1.0});
    lo = std::max(lo, x + 1.0);
  }
  free.push_back({lo, kFar});
  // Where it touches what it could rest on (row >= 1) or carry (row 0, which must also reach the surface).
  std::vector<Range> touch;
  const int32_t partner = row == 0 ? 1 : row - 1;
  for (double x : row_positions(pile, partner)) touch.push_back({x - 1.0, x + 1.0});
  if (or_carrying && row >= 1) {
    for (double x : row_positions(pile, row + 1)) touch.push_back({x - 1.0, x + 1.0});
  }
  std::vector<Range> useful = merged(touch);
  if (row == 0) useful = intersect(useful, {{-kFar, 0.0}});
  return intersect(useful, free);
}

std::vector<double> critical_positions(const core::Stack& pile, int32_t row, const Range& range) {
  std::vector<double> cuts{range.lo, range.hi};
  auto add = [&](double x) {
    if (x > range.lo && x < range.hi) cuts.push_back(x);
  };
  for (const auto& b : pile.blocks) {
    if (b.row == row - 1 || b.row == row + 1) {
      add(b.x - 1.0);  // the added block's right end meets this block's left end
      add(b.x);        // both left ends meet, so do both right ends: which end bounds the contact switches
      add(b.x + 1.0);  // the added block's left end meets this block's right end
    }
  }
  if (row == 0) {
    add(-1.0);  // the added block's right end passes the surface edge
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end(), [](double a, double b) { return b - a < 1e-12; }), cuts.end());
  return cuts;
}

double bounded_violation(const core::Stack& pile, const Placement& added, double position_tolerance) {
  const core::Stack stack = with_added(pile, {added});
  const int b = static_cast<int>(stack.blocks.size()) - 1;
  const core::ContactGraph g = core::build_contacts(stack, position_tolerance);
  core::opt::Problem problem;
  std::vector<int> row(g.size());
  for (size_t i = 0; i < g.size(); ++i) {
    row[i] = problem.add_row(1.0, 1.0);  // upward contact forces - downward = weight
    problem.add_row(0.0, 0.0);           // moments about the centre
  }
  const int bound = problem.add_row(-core::opt::kInfinity, 2.0 * static_cast<double>(g.size()));
  for (size_t k = 0; k < g.contacts.size(); ++k) {
    const core::Contact& c = g.contacts[k];
    const int v = problem.add_variable(0.0, core::opt::kInfinity, 0.0);
    problem.add_variable(0.0, core::opt::kInfinity, 0.0);
    const bool on_added = c.upper == b || c.lower == b;
    for (int end = 0; end < 2; ++end) {
      const double p = end == 0 ? c.left : c.right;
      const int ru = row[static_cast<size_t>(c.upper)];
      problem.set(ru, v + end, 1.0);
      problem.set(ru + 1, v + end, p - g.centre(c.upper));
      if (c.lower != core::kSurface) {
        const int rl = row[static_cast<size_t>(c.lower)];
        problem.set(rl, v + end, -1.0);
        problem.set(rl + 1, v + end, -(p - g.centre(c.lower)));
      }
      if (on_added) problem.set(bound, v + end, 1.0);
    }
  }
  // L1 slacks on the equilibrium rows (not on the bound): V = the least total residual.
  for (int r = 0; r < 2 * static_cast<int>(g.size()); ++r) {
    problem.set(r, problem.add_variable(0.0, core::opt::kInfinity, 1.0), 1.0);
    problem.set(r, problem.add_variable(0.0, core::opt::kInfinity, 1.0), -1.0);
  }
  static const std::unique_ptr<core::opt::Solver> solver = core::opt::make_solver("clp");
  const core::opt::SolveResult result = solver->solve(problem);
  if (result.status != core::opt::SolveStatus::kOptimal) {
    throw core::SolverError("bounded balance LP (clp): " + core::opt::to_string(result.status) + ": " + result.message);
  }
  return std::max(0.0, result.objective);
}

MinimumResult minimum_added(const core::Stack& pile, const SearchOptions& options) {
  core::validate(pile);
  if (pile.block_length != 1.0 || pile.table_edge != 0.0) {
    throw core::StackError("minimum_added needs a normalised pile (block_length 1, table_edge 0): use normalised()");
  }
  MinimumResult result;
  std::ostringstream summary;
  ++result.predictions;
  if (stands(pile, options.position_tolerance)) {
    result.minimum = 0;
    result.proven = true;
    result.summary = "0 (the pile stands as given)";
    return result;
  }
  if (options.max_added < 1) {
    result.summary = "not found: the pile falls and no blocks may be added";
    return result;
  }
  OneBlockSearch one(pile, options);
  const bool found = one.run();
  result.lp_evaluations = one.lp_evaluations_;
  result.predictions += one.predictions_;
  result.undecided = one.undecided_;
  if (found) {
    result.minimum = 1;
    result.proven = true;
    result.witness = {*one.witness_};
    summary << "1 (proven: the pile falls as given; " << result.lp_evaluations << " LPs)";
    result.summary = summary.str();
    return result;
  }
  const bool one_impossible = result.undecided == 0;
  for (int k = 2; k <= options.max_added; ++k) {
    std::vector<Placement> chosen;
    size_t evaluations = 0;
    const bool ok = grid_search(pile, k, options, chosen, evaluations);
    result.predictions += evaluations;
    if (ok) {
      result.minimum = k;
      result.witness = chosen;
      // Proven only when every smaller count is: 0 and 1 are, 2.. are not searched exhaustively.
      result.proven = k == 2 && one_impossible;
      summary << k << (result.proven ? " (proven: 0 and 1 impossible, " : " (not proven, ") << result.lp_evaluations
              << " LPs, " << result.undecided << " undecided pieces)";
      result.summary = summary.str();
      return result;
    }
  }
  summary << "not found up to " << options.max_added << " (1 " << (one_impossible ? "proven impossible" : "undecided")
          << "; larger counts: grid of " << options.pair_step << " found nothing)";
  result.summary = summary.str();
  return result;
}

std::vector<Placement> brute_force_witness(const core::Stack& pile, int count, double step, double position_tolerance,
                                           size_t* evaluations) {
  size_t local = 0;
  size_t& n = evaluations ? *evaluations : local;
  std::vector<Placement> chosen;
  std::function<bool(int)> search = [&](int remaining) -> bool {
    const core::Stack current = with_added(pile, chosen);
    double min_x = 0.0;
    double max_x = 0.0;
    int32_t top = -1;
    for (const auto& b : current.blocks) {
      min_x = std::min(min_x, b.x);
      max_x = std::max(max_x, b.x);
      top = std::max(top, b.row);
    }
    const long first = static_cast<long>(std::floor((min_x - 1.0) / step));
    const long last = static_cast<long>(std::ceil((max_x + 1.0) / step));
    for (int32_t row = 0; row <= top + 1; ++row) {
      for (long i = first; i <= last; ++i) {
        chosen.push_back({row, static_cast<double>(i) * step});
        const core::Stack candidate = with_added(pile, chosen);
        bool valid = true;
        try {
          core::validate(candidate);
        } catch (const core::StackError&) {
          valid = false;  // overlaps a block of its row
        }
        if (valid) {
          if (remaining == 1) {
            ++n;
            if (stands(candidate, position_tolerance)) return true;
          } else if (search(remaining - 1)) {
            return true;
          }
        }
        chosen.pop_back();
      }
    }
    return false;
  };
  if (count <= 0) return {};
  if (search(count)) return chosen;
  return {};
}

}  // namespace bricklayer::study
