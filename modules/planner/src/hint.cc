#include "bricklayer/planner/hint.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <utility>

#include "bricklayer/core/dynamics.h"
#include "bricklayer/core/predict.h"

namespace bricklayer::planner {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-6;  // keeps candidate blocks clear of knife-edge contacts with their neighbours

struct Interval {
  double lo, hi;
};

struct Outcome {
  bool valid = false;
  bool balanced = false;
  int moving = 0;
  double motion = 0.0;  // sum of a^2 + alpha^2 / 12 over blocks: how hard the pile wants to move
};

// Everything in normalised units: block length 1, surface edge at 0.
class Search {
 public:
  Search(const core::Stack& stack, const HintOptions& options) : stack_(stack), options_(options) {
    for (const core::Block& b : stack.blocks) {
      rows_.push_back(b.row);
      xs_.push_back((b.x - stack.table_edge) / stack.block_length);
      top_ = std::max(top_, static_cast<int>(b.row));
    }
  }

  int evaluations() const { return evaluations_; }
  int top() const { return top_; }
  double max_end() const {
    double e = -kInf;
    for (double x : xs_) e = std::max(e, x + 1.0);
    return e;
  }

  Outcome evaluate(const std::vector<SuggestedBlock>& added) {
    Outcome out;
    for (size_t i = 0; i < added.size(); ++i)
      if (!fits(added[i], added, i)) return out;
    out.valid = true;
    ++evaluations_;
    try {
      // The exact annotator's judge of motion (core dynamics), without the per-row cause analysis.
      const core::Accelerations acc = core::initial_accelerations(core::build_contacts(with_blocks(stack_, added)));
      out.balanced = !acc.any_moving();
      for (size_t i = 0; i < acc.a.size(); ++i) {
        out.moving += acc.moving(i) ? 1 : 0;
        out.motion += acc.a[i] * acc.a[i] + acc.alpha[i] * acc.alpha[i] / 12.0;
      }
    } catch (const std::runtime_error&) {
      out.balanced = false;
      out.moving = std::numeric_limits<int>::max();
      out.motion = kInf;
    }
    return out;
  }

  // Free places of a row: resting on the row below (or the surface) and clear of the row's blocks (and of
  // the other added blocks). Returns intervals of left ends.
  std::vector<Interval> free_intervals(int row, const std::vector<SuggestedBlock>& others) const {
    std::vector<Interval> support;
    if (row == 0) {
      double lo = 0.0;
      for (double x : xs_) lo = std::min(lo, x);
      support.push_back({lo - 2.0, 0.0});
    } else {
      for_each_block([&](int r, double x) {
        if (r == row - 1) support.push_back({x - 1.0, x + 1.0});
      }, others);
    }
    std::vector<Interval> blocked;
    for_each_block([&](int r, double x) {
      if (r == row) blocked.push_back({x - 1.0, x + 1.0});
    }, others);
    std::vector<Interval> free = merge(support);
    for (const Interval& b : merge(blocked)) {
      std::vector<Interval> next;
      for (const Interval& f : free) {
        if (b.hi <= f.lo || b.lo >= f.hi) {
          next.push_back(f);
          continue;
        }
        if (f.lo < b.lo) next.push_back({f.lo, b.lo});
        if (b.hi < f.hi) next.push_back({b.hi, f.hi});
      }
      free = next;
    }
    std::vector<Interval> out;
    for (const Interval& f : free)
      if (f.hi - f.lo > 2 * kEps) out.push_back({f.lo + kEps, f.hi - kEps});
    return out;
  }

  static std::vector<Interval> intersect(const std::vector<Interval>& a, Interval b) {
    std::vector<Interval> out;
    for (const Interval& i : a) {
      const double lo = std::max(i.lo, b.lo), hi = std::min(i.hi, b.hi);
      if (hi > lo) out.push_back({lo, hi});
    }
    return out;
  }

 private:
  template <typename F>
  void for_each_block(F f, const std::vector<SuggestedBlock>& others) const {
    for (size_t i = 0; i < xs_.size(); ++i) f(rows_[i], xs_[i]);
    for (const SuggestedBlock& b : others) f(b.row, b.x);
  }

  static std::vector<Interval> merge(std::vector<Interval> v) {
    std::sort(v.begin(), v.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
    std::vector<Interval> out;
    for (const Interval& i : v) {
      if (!out.empty() && i.lo <= out.back().hi) out.back().hi = std::max(out.back().hi, i.hi);
      else out.push_back(i);
    }
    return out;
  }

  // No overlap with the row's blocks (stack validation would reject it); support is predict()'s business.
  bool fits(const SuggestedBlock& b, const std::vector<SuggestedBlock>& added, size_t self) const {
    if (b.row < 0 || !std::isfinite(b.x)) return false;
    for (size_t i = 0; i < xs_.size(); ++i)
      if (rows_[i] == b.row && std::abs(xs_[i] - b.x) < 1.0 - 1e-9) return false;
    for (size_t i = 0; i < added.size(); ++i)
      if (i != self && added[i].row == b.row && std::abs(added[i].x - b.x) < 1.0 - 1e-9) return false;
    return true;
  }

  const core::Stack& stack_;
  const HintOptions& options_;
  std::vector<int> rows_;
  std::vector<double> xs_;
  int top_ = -1;
  int evaluations_ = 0;
};

struct Candidate {
  std::vector<SuggestedBlock> blocks;
  double value = -kInf;  // overhang after
};

// The rightmost safe x of block `index` of `blocks` inside [lo, hi] (other blocks fixed). Scans balance on a grid
// of step 2m from the right: if the balanced positions near the answer form an interval (they do on every
// pile we tried), any safe grid position of step m lies in a balanced interval of width >= 2m, which this
// grid cannot miss. The right end x* of the first balanced interval found is refined by bisection (to 2m/128)
// and x* - m is checked at x* - 2m, x* - m (and the other blocks' shifts). stop_below: give up once the
// answer's right end cannot exceed this. on_grid(x, outcome) sees every grid evaluation.
template <typename OnGrid>
std::optional<double> rightmost_safe(Search& search, std::vector<SuggestedBlock> blocks, size_t index, Interval range,
                                     double m, double stop_below, OnGrid on_grid) {
  auto balanced = [&](double x) {
    blocks[index].x = x;
    return search.evaluate(blocks).balanced;
  };
  auto others_safe = [&](double x) {
    for (size_t j = 0; j < blocks.size(); ++j) {
      if (j == index) continue;
      for (double s : {-m, m}) {
        std::vector<SuggestedBlock> shifted = blocks;
        shifted[index].x = x;
        shifted[j].x += s;
        if (!search.evaluate(shifted).balanced) return false;
      }
    }
    return true;
  };
  const double lo = range.lo, step = 2 * m;
  double x = range.hi;
  std::optional<double> unbalanced;  // nearest grid position to the right of x known to be unbalanced
  while (x - m >= lo) {
    if (x + step - m + 1.0 <= stop_below) return std::nullopt;
    blocks[index].x = x;
    const Outcome o = search.evaluate(blocks);
    on_grid(x, o);
    if (!(o.valid && o.balanced)) {
      unbalanced = x;
      x -= step;
      continue;
    }
    double good = x;
    if (unbalanced) {
      double bad = *unbalanced;
      for (int it = 0; it < 7; ++it) {
        const double mid = 0.5 * (good + bad);
        (balanced(mid) ? good : bad) = mid;
      }
    }
    const double candidate = good - m;
    if (candidate - m >= lo && balanced(candidate) && balanced(candidate - m) && others_safe(candidate))
      return candidate;
    unbalanced = candidate - m;  // (or candidate itself): scan on to the left of it
    x = candidate - m - step;
  }
  return std::nullopt;
}

double value_of(double max_end, const std::vector<SuggestedBlock>& blocks) {
  double v = max_end;
  for (const SuggestedBlock& b : blocks) v = std::max(v, b.x + 1.0);
  return v;
}

Hint finish(const core::Stack& stack, Hint::Kind kind, const Candidate& best, const HintOptions& options,
            const Search& search) {
  Hint hint;
  hint.margin = options.margin;
  hint.evaluations = search.evaluations();
  if (best.blocks.empty()) return hint;
  hint.kind = kind;
  hint.blocks = best.blocks;
  hint.overhang_after = best.value;
  hint.score_after = core::score_of(best.value);
  return hint;
}

}  // namespace

core::Stack with_blocks(const core::Stack& stack, const std::vector<SuggestedBlock>& blocks) {
  core::Stack out = stack;
  int64_t id = 0;
  for (const core::Block& b : stack.blocks) id = std::max(id, b.id);
  for (const SuggestedBlock& b : blocks) out.blocks.push_back({++id, b.row, stack.table_edge + b.x * stack.block_length});
  return out;
}

Hint next_block_hint(const core::Stack& stack, const HintOptions& options) {
  core::validate(stack);
  if (!(options.margin > 0) || !std::isfinite(options.margin))
    throw std::invalid_argument("next_block_hint: margin must be positive");
  Search search(stack, options);
  const double m = options.margin;
  const double end = search.max_end();
  const core::Prediction now = core::predict(stack);

  if (now.balanced) {
    // Rows in order of how far a block there could reach.
    struct RowPlan {
      int row;
      std::vector<Interval> free;
      double reach;
    };
    std::vector<RowPlan> plans;
    for (int r = 0; r <= search.top() + 1; ++r) {
      RowPlan p{r, search.free_intervals(r, {}), -kInf};
      for (const Interval& i : p.free) p.reach = std::max(p.reach, i.hi + 1.0);
      if (!p.free.empty()) plans.push_back(std::move(p));
    }
    std::sort(plans.begin(), plans.end(), [](const RowPlan& a, const RowPlan& b) { return a.reach > b.reach; });
    Candidate best;
    for (const RowPlan& p : plans) {
      if (!best.blocks.empty() && std::max(end, p.reach) <= best.value + 1e-12) break;
      for (auto it = p.free.rbegin(); it != p.free.rend(); ++it) {
        if (!best.blocks.empty() && std::max(end, it->hi + 1.0) <= best.value + 1e-12) break;
        const double stop_below = best.blocks.empty() ? -kInf : best.value;
        const auto x = rightmost_safe(search, {{p.row, 0.0}}, 0, *it, m, stop_below, [](double, const Outcome&) {});
        if (!x) continue;
        const std::vector<SuggestedBlock> blocks{{p.row, *x}};
        const double v = value_of(end, blocks);
        if (best.blocks.empty() || v > best.value + 1e-12) best = {blocks, v};
        break;  // intervals further left in this row reach less far
      }
    }
    return finish(stack, Hint::Kind::kExtend, best, options, search);
  }

  // Unbalanced: blocks touching a cause (on it or under it), one first, then two.
  std::vector<int64_t> moving_ids = now.causes();  // what the player must fix
  std::map<int, std::vector<Interval>> near;  // row -> x ranges next to a moving block
  for (size_t i = 0; i < stack.blocks.size(); ++i) {
    const core::Block& b = stack.blocks[i];
    if (std::find(moving_ids.begin(), moving_ids.end(), b.id) == moving_ids.end()) continue;
    const double x = (b.x - stack.table_edge) / stack.block_length;
    for (int r : {b.row - 1, b.row + 1})
      if (r >= 0) near[r].push_back({x - 1.0, x + 1.0});
  }
  struct Single {
    SuggestedBlock block;
    double motion;
  };
  std::vector<Single> singles;
  Candidate best;
  for (const auto& [row, ranges] : near) {
    const std::vector<Interval> free = search.free_intervals(row, {});
    for (const Interval& range : ranges)
      for (const Interval& f : Search::intersect(free, range)) {
        const auto x = rightmost_safe(search, {{row, 0.0}}, 0, f, m, -kInf, [&](double gx, const Outcome& o) {
          if (o.valid) singles.push_back({{row, gx}, o.motion});
        });
        if (!x) continue;
        const std::vector<SuggestedBlock> blocks{{row, *x}};
        const double v = value_of(end, blocks);
        if (best.blocks.empty() || v > best.value + 1e-12) best = {blocks, v};
      }
  }
  if (!best.blocks.empty() || options.max_added < 2) return finish(stack, Hint::Kind::kRebalance, best, options, search);

  // Two blocks: the most helpful single blocks (least motion left) as first blocks.
  std::stable_sort(singles.begin(), singles.end(), [](const Single& a, const Single& b) { return a.motion < b.motion; });
  std::vector<SuggestedBlock> firsts;
  for (const Single& s : singles) {
    if (static_cast<int>(firsts.size()) >= options.pair_seeds) break;
    bool distinct = true;
    for (const SuggestedBlock& f : firsts)
      if (f.row == s.block.row && std::abs(f.x - s.block.x) < 0.1) distinct = false;
    if (distinct) firsts.push_back(s.block);
  }
  for (const SuggestedBlock& first : firsts) {
    const std::vector<SuggestedBlock> one{first};
    const core::Prediction p = core::predict(with_blocks(stack, one));
    std::vector<int64_t> still = p.moving();
    const core::Stack grown = with_blocks(stack, one);
    std::map<int, std::vector<Interval>> near2;
    for (size_t i = 0; i < grown.blocks.size(); ++i) {
      const core::Block& b = grown.blocks[i];
      const bool is_first = i + 1 == grown.blocks.size();
      if (!is_first && std::find(still.begin(), still.end(), b.id) == still.end()) continue;
      const double x = (b.x - stack.table_edge) / stack.block_length;
      for (int r : {b.row - 1, b.row + 1})
        if (r >= 0) near2[r].push_back({x - 1.0, x + 1.0});
    }
    for (const auto& [row, ranges] : near2) {
      const std::vector<Interval> free = search.free_intervals(row, one);
      for (const Interval& range : ranges)
        for (const Interval& f : Search::intersect(free, range)) {
          const auto x = rightmost_safe(search, {first, {row, 0.0}}, 1, f, m, -kInf, [](double, const Outcome&) {});
          if (!x) continue;
          const std::vector<SuggestedBlock> blocks{first, {row, *x}};
          const double v = value_of(end, blocks);
          if (best.blocks.empty() || v > best.value + 1e-12) best = {blocks, v};
        }
    }
  }
  return finish(stack, Hint::Kind::kRebalance, best, options, search);
}

}  // namespace bricklayer::planner
