#include "bricklayer/study/checker.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "bricklayer/core/predict.h"

namespace bricklayer::study {

std::string to_string(Outcome outcome) {
  switch (outcome) {
    case Outcome::kCorrect: return "correct";
    case Outcome::kExcess: return "excess";
    case Outcome::kFailed: return "failed";
  }
  return "failed";
}

StabiliseChecker::StabiliseChecker(Problem problem, const SearchOptions& search) : problem_(std::move(problem)) {
  if (problem_.kind != ProblemKind::kStabilise) throw ProblemError(problem_.name + ": not a stabilise problem");
  SearchOptions options = search;
  options.position_tolerance = problem_.position_tolerance;
  options.max_added = problem_.max_added;
  minimum_ = minimum_added(problem_.pile, options);
  if (!stands(with_added(problem_.pile, problem_.solution), problem_.position_tolerance)) {
    throw ProblemError(problem_.name + ": the declared solution does not stand");
  }
  if (minimum_.minimum != problem_.minimum_added || !minimum_.proven) {
    throw ProblemError(problem_.name + ": the file says " + std::to_string(problem_.minimum_added) +
                       " added blocks suffice at the fewest, the search says " + minimum_.summary);
  }
}

Verdict StabiliseChecker::check(const core::Stack& final_pile, int64_t time_ms) const {
  Verdict v;
  v.minimum_added = minimum_.minimum;
  v.time_ms = time_ms;
  core::Stack pile;
  try {
    core::validate(final_pile);
    pile = normalised(final_pile);
  } catch (const core::StackError& e) {
    v.reason = std::string("the pile could not be judged: ") + e.what();
    return v;
  }
  v.score = core::score_of(core::overhang(pile));
  // Match every given block to the nearest unused block of its row (given blocks in order of position).
  std::vector<char> used(pile.blocks.size(), 0);
  std::vector<const core::Block*> given;
  for (const auto& b : problem_.pile.blocks) given.push_back(&b);
  std::sort(given.begin(), given.end(), [](const core::Block* a, const core::Block* b) {
    return a->row < b->row || (a->row == b->row && a->x < b->x);
  });
  for (const core::Block* g : given) {
    int best = -1;
    double best_d = problem_.match_tolerance;
    for (size_t i = 0; i < pile.blocks.size(); ++i) {
      if (used[i] || pile.blocks[i].row != g->row) continue;
      const double d = std::abs(pile.blocks[i].x - g->x);
      if (d <= best_d) {
        best = static_cast<int>(i);
        best_d = d;
      }
    }
    if (best < 0) {
      std::ostringstream out;
      out << "the given block of row " << g->row << " at x = " << g->x << " was moved or removed";
      v.reason = out.str();
      v.blocks_added = static_cast<int32_t>(pile.blocks.size()) - static_cast<int32_t>(problem_.pile.blocks.size());
      v.stands = stands(pile, problem_.position_tolerance);
      return v;
    }
    used[static_cast<size_t>(best)] = 1;
  }
  v.blocks_added = static_cast<int32_t>(pile.blocks.size() - problem_.pile.blocks.size());
  v.stands = stands(pile, problem_.position_tolerance);
  std::ostringstream out;
  if (!v.stands) {
    out << "falls with " << v.blocks_added << " added block" << (v.blocks_added == 1 ? "" : "s");
    v.outcome = Outcome::kFailed;
  } else if (v.blocks_added > v.minimum_added) {
    out << "stands with " << v.blocks_added << " added blocks; " << v.minimum_added << " suffice";
    v.outcome = Outcome::kExcess;
  } else {
    out << "stands with " << v.blocks_added << " added block" << (v.blocks_added == 1 ? "" : "s")
        << ", the fewest possible";
    // Fewer than the proven minimum can only be a measurement at the tolerance's edge: still correct, said.
    if (v.blocks_added < v.minimum_added) out << " (below the computed minimum of " << v.minimum_added << ": check the measurement)";
    v.outcome = Outcome::kCorrect;
  }
  v.reason = out.str();
  return v;
}

ScoreJudge::ScoreJudge(Problem problem) : problem_(std::move(problem)) {
  if (problem_.kind != ProblemKind::kScore) throw ProblemError(problem_.name + ": not a score problem");
}

void ScoreJudge::start(int64_t utime) {
  start_ = utime;
  last_ = utime;
}

void ScoreJudge::observe(int64_t utime, int32_t num_blocks, bool balanced, int32_t score) {
  if (!start_) start(utime);
  if (last_ && utime < *last_) return;
  last_ = utime;
  if (solved_ms_) return;
  const int64_t limit_utime = *start_ + problem_.time_limit_ms * 1000;
  if (utime > limit_utime) return;
  last_blocks_ = num_blocks;
  const bool within_blocks = num_blocks <= problem_.max_blocks;
  if (balanced && within_blocks) best_score_ = std::max(best_score_, score);
  const bool goal = balanced && within_blocks && score >= problem_.min_score;
  if (!goal) {
    held_since_.reset();
    return;
  }
  if (!held_since_) held_since_ = utime;
  if (utime - *held_since_ >= problem_.hold_ms * 1000) solved_ms_ = (*held_since_ - *start_) / 1000;
}

bool ScoreJudge::timed_out(int64_t utime) const {
  return !solved_ms_ && start_ && utime - *start_ >= problem_.time_limit_ms * 1000;
}

Verdict ScoreJudge::verdict(int64_t utime) const {
  Verdict v;
  v.blocks_added = last_blocks_;
  v.score = best_score_;
  std::ostringstream out;
  if (solved_ms_) {
    v.outcome = Outcome::kCorrect;
    v.stands = true;
    v.time_ms = *solved_ms_;
    out << "reached " << problem_.min_score << " points with at most " << problem_.max_blocks << " blocks after "
        << std::fixed;
    out.precision(1);
    out << static_cast<double>(*solved_ms_) / 1000.0 << " s";
  } else {
    v.outcome = Outcome::kFailed;
    v.time_ms = start_ ? std::min<int64_t>((utime - *start_) / 1000, problem_.time_limit_ms) : 0;
    out << "not reached: best standing score with at most " << problem_.max_blocks << " blocks was " << best_score_;
  }
  v.reason = out.str();
  return v;
}

}  // namespace bricklayer::study
