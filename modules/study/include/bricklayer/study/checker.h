// Judging a subject's answer to a study problem.
//
// Stabilise problems: when the subject says done, the final pile (as measured) is compared with the
// given pile. Every given block must still be there: a block of the same row within match_tolerance of
// its position (vision numbers blocks by itself, so ids are not used). The other blocks are the added
// ones. The pile must stand (exact annotator, with the problem's position tolerance, as every measured
// pile is judged). Outcome: failed when a given block is missing or the pile falls; correct when it
// stands with the fewest blocks possible (the minimum is computed by minimum_added(), not taken from the
// file); excess when it stands with more.
//
// Score problems: fed the pile's verdicts in time order (one per prediction), solved once a pile of at
// most max_blocks blocks has stood with a score of at least min_score for hold_ms without a break, within
// the time limit.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "bricklayer/core/stack.h"
#include "bricklayer/study/placement.h"
#include "bricklayer/study/problem.h"

namespace bricklayer::study {

enum class Outcome { kCorrect = 1, kExcess = 2, kFailed = 3 };  // same values as study_answer_t::OUTCOME_*
std::string to_string(Outcome outcome);

struct Verdict {
  Outcome outcome = Outcome::kFailed;
  bool stands = false;
  int32_t blocks_added = 0;    // stabilise: blocks beyond the given ones; score: blocks in the pile
  int32_t minimum_added = -1;  // stabilise: the computed minimum; score: -1
  int32_t score = 0;           // of the final pile
  int64_t time_ms = 0;         // problem start -> answer (score: -> goal first held; the limit when not solved)
  std::string reason;          // one line for the experimenter
};

class StabiliseChecker {
 public:
  // Computes the minimum (may take a second or two on a large pile). Throws ProblemError when the
  // problem is not a stabilise problem, the declared solution does not stand, or the declared minimum
  // disagrees with the computed one (a problem file must say what is true).
  explicit StabiliseChecker(Problem problem, const SearchOptions& search = {});

  const Problem& problem() const { return problem_; }
  const MinimumResult& minimum() const { return minimum_; }

  // `final_pile` in any units (normalised here). A pile that fails validation (overlapping blocks, NaN)
  // is a failed answer with the reason, not an exception.
  Verdict check(const core::Stack& final_pile, int64_t time_ms = 0) const;

 private:
  Problem problem_;
  MinimumResult minimum_;
};

class ScoreJudge {
 public:
  explicit ScoreJudge(Problem problem);  // throws ProblemError unless a score problem

  // One verdict on the pile, utime in microseconds from any clock (the first call starts the problem's
  // clock unless start() was called). Observations must come in time order; an older one is ignored.
  void start(int64_t utime);
  void observe(int64_t utime, int32_t num_blocks, bool balanced, int32_t score);

  bool solved() const { return solved_ms_.has_value(); }
  bool timed_out(int64_t utime) const;  // the limit passed without the goal held
  // The verdict now (or when time is up): correct when solved, else failed.
  Verdict verdict(int64_t utime) const;

 private:
  Problem problem_;
  std::optional<int64_t> start_;
  std::optional<int64_t> held_since_;  // utime the current unbroken run of goal piles began
  std::optional<int64_t> last_;
  std::optional<int64_t> solved_ms_;   // problem start -> goal held, milliseconds
  int32_t best_score_ = 0;             // best score of a standing pile within the block limit
  int32_t last_blocks_ = 0;
};

}  // namespace bricklayer::study
