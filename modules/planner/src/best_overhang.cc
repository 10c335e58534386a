#include "bricklayer/planner/best_overhang.h"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <stdexcept>

namespace bricklayer::planner {
namespace {

constexpr int kTable = -1;

struct Contact {
  int lower;  // block index or kTable
  int upper;
};

// The problem for one layout: variables v = [x_0..x_{n-1}, f_0, m_0, f_1, m_1, ...].
struct Problem {
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

double objective(unsigned nv, const double* v, double* grad, void* data) {
  const auto* p = static_cast<const Problem*>(data);
  if (grad) {
    std::fill(grad, grad + nv, 0.0);
    grad[p->target] = 1.0;
  }
  return v[p->target] + 1.0;
}

double distance_to_start(unsigned nv, const double* v, double* grad, void* data) {
  const auto* p = static_cast<const Problem*>(data);
  if (grad) std::fill(grad, grad + nv, 0.0);
  double sum = 0.0;
  for (int i = 0; i < p->n(); ++i) {
    const double d = v[i] - p->start[i];
    sum += 0.5 * d * d;
    if (grad) grad[i] = d;
  }
  return sum;
}

// Equilibrium of every block: force (f from below - f to above - 1 = 0) and moment about x = 0.
void equalities(unsigned m, double* result, unsigned nv, const double* v, double* grad, void* data) {
  const auto* p = static_cast<const Problem*>(data);
  const int n = p->n();
  for (int i = 0; i < n; ++i) {
    result[2 * i] = -1.0;
    result[2 * i + 1] = -(v[i] + 0.5);
  }
  if (grad) {
    std::fill(grad, grad + static_cast<size_t>(m) * nv, 0.0);
    for (int i = 0; i < n; ++i) grad[static_cast<size_t>(2 * i + 1) * nv + i] = -1.0;
  }
  for (size_t c = 0; c < p->contacts.size(); ++c) {
    const Contact& k = p->contacts[c];
    const int fi = p->f_index(c), mi = p->m_index(c);
    result[2 * k.upper] += v[fi];
    result[2 * k.upper + 1] += v[mi];
    if (grad) {
      grad[static_cast<size_t>(2 * k.upper) * nv + fi] += 1.0;
      grad[static_cast<size_t>(2 * k.upper + 1) * nv + mi] += 1.0;
    }
    if (k.lower != kTable) {
      result[2 * k.lower] -= v[fi];
      result[2 * k.lower + 1] -= v[mi];
      if (grad) {
        grad[static_cast<size_t>(2 * k.lower) * nv + fi] -= 1.0;
        grad[static_cast<size_t>(2 * k.lower + 1) * nv + mi] -= 1.0;
      }
    }
  }
}

// The resultant's point of application lies in both blocks (and on the surface, x <= 0); neighbours in one
// row do not overlap. All of the form g(v) <= 0.
void inequalities(unsigned m, double* result, unsigned nv, const double* v, double* grad, void* data) {
  const auto* p = static_cast<const Problem*>(data);
  if (grad) std::fill(grad, grad + static_cast<size_t>(m) * nv, 0.0);
  unsigned k = 0;
  auto row = [&](unsigned r) { return grad + static_cast<size_t>(r) * nv; };
  for (size_t c = 0; c < p->contacts.size(); ++c) {
    const Contact& contact = p->contacts[c];
    const int fi = p->f_index(c), mi = p->m_index(c);
    const double f = v[fi], mom = v[mi];
    auto within_block = [&](int b) {
      // f * x_b - m <= 0
      result[k] = f * v[b] - mom;
      if (grad) {
        row(k)[b] = f;
        row(k)[fi] = v[b];
        row(k)[mi] = -1.0;
      }
      ++k;
      // m - f * (x_b + 1) <= 0
      result[k] = mom - f * (v[b] + 1.0);
      if (grad) {
        row(k)[b] = -f;
        row(k)[fi] = -(v[b] + 1.0);
        row(k)[mi] = 1.0;
      }
      ++k;
    };
    within_block(contact.upper);
    if (contact.lower == kTable) {
      result[k] = mom;  // m - f * 0 <= 0: the point is on the surface
      if (grad) row(k)[mi] = 1.0;
      ++k;
    } else {
      within_block(contact.lower);
    }
  }
  for (const auto& [left, right] : p->same_row) {
    result[k] = 1.0 + v[left] - v[right];
    if (grad) {
      row(k)[left] = 1.0;
      row(k)[right] = -1.0;
    }
    ++k;
  }
}

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

}  // namespace

std::optional<OverhangStack> optimise_layout(const std::vector<PlacedBlock>& start_unsorted, int target,
                                             double tolerance, bool feasibility_phase) {
  if (start_unsorted.empty()) return std::nullopt;
  if (target < 0 || target >= static_cast<int>(start_unsorted.size()))
    throw std::invalid_argument("optimise_layout: target " + std::to_string(target) + " out of range");
  // Sort while remembering the target.
  std::vector<int> order(start_unsorted.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const PlacedBlock &pa = start_unsorted[a], &pb = start_unsorted[b];
    return pa.row != pb.row ? pa.row < pb.row : pa.x < pb.x;
  });
  std::vector<PlacedBlock> start;
  Problem problem;
  for (size_t i = 0; i < order.size(); ++i) {
    start.push_back(start_unsorted[order[i]]);
    if (order[i] == target) problem.target = static_cast<int>(i);
  }
  const int n = static_cast<int>(start.size());
  for (const PlacedBlock& b : start) problem.rows.push_back(b.row);
  for (int i = 0; i < n; ++i) {
    if (start[i].row == 0) problem.contacts.push_back({kTable, i});
    if (i + 1 < n && start[i + 1].row == start[i].row) problem.same_row.emplace_back(i, i + 1);
    for (int j = 0; j < n; ++j)
      if (start[j].row == start[i].row + 1 && std::abs(start[j].x - start[i].x) < 1.6)
        problem.contacts.push_back({i, j});
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

  // Start forces: each block's load (own weight + what rests on it) shared among its supports in proportion to
  // the overlap, acting at the overlap's middle. Force equilibrium and the interval constraints then hold at
  // the start; only moments are off, which SLSQP repairs far more reliably than from zero forces.
  {
    std::vector<double> load(n, 1.0);
    const int top_row = start.back().row;
    for (int r = top_row; r >= 0; --r)
      for (int i = 0; i < n; ++i) {
        if (start[i].row != r) continue;
        std::vector<std::pair<size_t, double>> below;  // contact, overlap
        double total = 0.0;
        for (size_t c = 0; c < problem.contacts.size(); ++c) {
          const Contact& k = problem.contacts[c];
          if (k.upper != i) continue;
          const double lo = k.lower == kTable ? start[i].x : std::max(start[i].x, start[k.lower].x);
          const double hi = k.lower == kTable ? std::min(start[i].x + 1.0, 0.0) : std::min(start[i].x, start[k.lower].x) + 1.0;
          if (hi <= lo) continue;
          below.emplace_back(c, hi - lo);
          total += hi - lo;
        }
        for (const auto& [c, overlap] : below) {
          const Contact& k = problem.contacts[c];
          const double f = load[i] * overlap / total;
          const double lo = k.lower == kTable ? start[i].x : std::max(start[i].x, start[k.lower].x);
          v[problem.f_index(c)] = f;
          v[problem.m_index(c)] = f * (lo + 0.5 * overlap);
          if (k.lower != kTable) load[k.lower] += f;
        }
      }
  }

  auto residual_of = [&](const std::vector<double>& w) {
    std::vector<double> eq(2 * n), ineq(problem.num_inequalities());
    equalities(static_cast<unsigned>(eq.size()), eq.data(), nv, w.data(), nullptr, &problem);
    inequalities(static_cast<unsigned>(ineq.size()), ineq.data(), nv, w.data(), nullptr, &problem);
    double r = 0.0;
    for (double e : eq) r = std::max(r, std::abs(e));
    for (double g : ineq) r = std::max(r, g);
    for (int i = 0; i < nv; ++i) r = std::max({r, lower[i] - w[i], w[i] - upper[i]});
    return r;
  };
  // feasibility: find a balanced layout near the start (min distance of positions to the start) instead of
  // maximising the overhang.
  auto run = [&](std::vector<double>& w, bool feasibility) {
    nlopt::opt opt(nlopt::LD_SLSQP, static_cast<unsigned>(nv));
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(upper);
    if (feasibility) opt.set_min_objective(distance_to_start, &problem);
    else opt.set_max_objective(objective, &problem);
    opt.add_equality_mconstraint(equalities, &problem, std::vector<double>(2 * n, 1e-12));
    opt.add_inequality_mconstraint(inequalities, &problem, std::vector<double>(problem.num_inequalities(), 1e-12));
    opt.set_xtol_rel(1e-12);
    opt.set_ftol_abs(1e-14);
    opt.set_maxeval(3000);
    double value = 0.0;
    try {
      opt.optimize(w, value);
    } catch (const std::exception&) {
      // roundoff_limited or a failed QP subproblem: w holds the last iterate; the residual decides.
    }
  };
  problem.start = v;
  std::vector<double> w = v;
  run(w, false);
  // NLopt calls infeasible ends a success: measure the residual ourselves. Far-from-balanced starts often end
  // infeasible: then first find a balanced layout near the start, and maximise from there.
  double residual = residual_of(w);
  if (!(residual <= tolerance) && feasibility_phase) {
    w = v;
    run(w, true);
    if (!(residual_of(w) <= 1e-6)) return std::nullopt;
    run(w, false);
    residual = residual_of(w);
  }
  if (!(residual <= tolerance)) return std::nullopt;
  v = w;

  OverhangStack out;
  out.residual = residual;
  for (int i = 0; i < n; ++i) out.blocks.push_back({start[i].row, v[i]});
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

std::vector<OverhangStack> search_best_overhang(int n_max, const OverhangSearchOptions& options,
                                                const std::function<void(int, const OverhangStack&)>& progress) {
  if (n_max < 1) throw std::invalid_argument("search_best_overhang: n_max must be at least 1");
  std::mt19937_64 rng(options.seed);
  std::vector<OverhangStack> best_per_n;
  std::vector<OverhangStack> beam;
  if (options.resume_from.empty()) {
    OverhangStack one;
    one.blocks = {{0, -0.5}};
    one.overhang = 0.5;
    best_per_n.push_back(one);
  } else {
    best_per_n = options.resume_from;
  }
  for (size_t k = 0; k < best_per_n.size(); ++k) {
    if (best_per_n[k].blocks.size() != k + 1)
      throw std::invalid_argument("search_best_overhang: resume_from[" + std::to_string(k) + "] does not have " +
                                  std::to_string(k + 1) + " blocks");
    if (progress) progress(static_cast<int>(k + 1), best_per_n[k]);
  }
  beam.push_back(best_per_n.back());
  for (int n = static_cast<int>(best_per_n.size()) + 1; n <= n_max; ++n) {
    std::map<std::string, OverhangStack> found;
    auto consider = [&](const std::vector<PlacedBlock>& seed, bool far_from_balanced = false) {
      auto result = optimise_layout(seed, rightmost(seed), options.tolerance, far_from_balanced);
      if (!result) return;
      auto [it, inserted] = found.emplace(shape_key(*result), *result);
      if (!inserted && result->overhang > it->second.overhang) it->second = *result;
    };
    for (const OverhangStack& s : beam)
      for (const auto& seed : grown(s.blocks)) consider(seed);
    if (n >= 8)
      for (const auto& seed : wall_seeds(n, options.wall_seeds, rng)) consider(seed, true);
    // Seeded restarts around the best few.
    std::vector<OverhangStack> ranked;
    for (auto& [key, s] : found) ranked.push_back(s);
    std::sort(ranked.begin(), ranked.end(),
              [](const OverhangStack& a, const OverhangStack& b) { return a.overhang > b.overhang; });
    std::normal_distribution<double> noise(0.0, 0.08);
    const size_t top_few = std::min<size_t>(ranked.size(), 2);
    for (size_t i = 0; i < top_few; ++i)
      for (int k = 0; k < options.perturbations; ++k) {
        std::vector<PlacedBlock> seed = ranked[i].blocks;
        for (PlacedBlock& b : seed) b.x += noise(rng);
        consider(sorted_blocks(seed));
      }
    ranked.clear();
    for (auto& [key, s] : found) ranked.push_back(s);
    std::sort(ranked.begin(), ranked.end(),
              [](const OverhangStack& a, const OverhangStack& b) { return a.overhang > b.overhang; });
    // Polish the best: positions moved, so rebuild the contact set from them and optimise again.
    for (size_t i = 0; i < std::min<size_t>(ranked.size(), options.beam); ++i)
      for (int round = 0; round < 3; ++round) {
        auto again = optimise_layout(ranked[i].blocks, rightmost(ranked[i].blocks), options.tolerance);
        if (!again || again->overhang <= ranked[i].overhang + 1e-9) break;
        ranked[i] = *again;
      }
    std::sort(ranked.begin(), ranked.end(),
              [](const OverhangStack& a, const OverhangStack& b) { return a.overhang > b.overhang; });
    {
      // Always a candidate: the best of n-1 plus a block lying on the surface far to the left (still balanced),
      // so the table never decreases with n even when nothing better converges.
      OverhangStack fallback = best_per_n.back();
      double left = 0.0;
      for (const PlacedBlock& b : fallback.blocks) left = std::min(left, b.x);
      fallback.blocks.insert(fallback.blocks.begin(), PlacedBlock{0, left - 2.0});
      auto at = std::find_if(ranked.begin(), ranked.end(),
                             [&](const OverhangStack& r) { return r.overhang < fallback.overhang; });
      ranked.insert(at, fallback);
    }
    beam.assign(ranked.begin(), ranked.begin() + std::min<size_t>(ranked.size(), options.beam));
    best_per_n.push_back(beam.front());
    if (progress) progress(n, beam.front());
  }
  return best_per_n;
}

}  // namespace bricklayer::planner
