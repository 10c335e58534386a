// A study problem on the board (study_problem_t on BL_STUDY_PROBLEM, from the study's session driver):
// a stabilise problem's pile drawn as block outlines at the blocks' board positions, so the subject puts
// real blocks into them, and a score problem's target (points, blocks allowed, time left) as a line of
// text. Pure (no SDL, no bus): what is shown is decided here, GameRenderer draws it.
//
// A problem is shown while it is current: heard within kHeardUs (the driver republishes it once a second
// while its step runs), and the session it names heard within kHeardUs too, on that problem's step
// (problem n = STEP_PROBLEM_1 + n - 1), running or paused. So the outlines go at once when the step ends
// (the answer is taken, the experimenter aborts) and three missed seconds after the driver falls silent.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/board/board_to_projector.h"
#include "bricklayer/study_problem_t.hpp"
#include "bricklayer/study_session_t.hpp"

namespace bricklayer::projection {

// One block of a stabilise problem's pile: board block lengths, left end x from the surface edge, row 0 on
// the surface (its bottom at row * block height, the drawn stack's height).
struct ProblemBlock {
  int row = 0;
  double x = 0;
  bool operator==(const ProblemBlock& o) const { return row == o.row && x == o.x; }
};

// What the board shows of the current problem; both empty = nothing.
struct ProblemView {
  std::vector<ProblemBlock> outlines;  // a stabilise problem's pile
  std::string target;                  // a score problem's target, e.g. "TARGET 100 points with at most 4 blocks - 0:58 left"
  bool empty() const { return outlines.empty() && target.empty(); }
  bool operator==(const ProblemView& o) const { return outlines == o.outlines && target == o.target; }
  bool operator!=(const ProblemView& o) const { return !(*this == o); }
};

// Why a problem cannot be drawn ("" = it can): num_blocks disagreeing with its blocks, an unknown kind or
// problem number, a stabilise pile that is empty or larger than kMaxProblemBlocks, a block with a
// non-finite x or one beyond kMaxProblemX, a row outside 0..kMaxProblemRow, a negative time limit, a score
// problem's negative points or blocks allowed outside 1..kMaxProblemBlocks.
inline constexpr int kMaxProblemBlocks = 100;
inline constexpr int kMaxProblemRow = 100;
inline constexpr double kMaxProblemX = 1000;
std::string problem_fault(const study_problem_t& problem);

// The score problem's line: "TARGET 100 points with at most 4 blocks", and " - 0:42 left" when limited.
std::string score_target_text(int min_score, int max_blocks, std::optional<int64_t> remaining_ms);

// The outline of one block as four quadrilaterals in projector pixels (bottom, right, top, left sides), a
// ring `thickness_px` wide lying just inside the block's mapped edges: a real block put exactly in place
// covers all of it. Corners in order around each quadrilateral; pixel centres at integers (OpenCV's
// convention, as BoardToProjector maps).
std::array<std::array<board::Point2, 4>, 4> outline_ring(const ProblemBlock& block, double block_height,
                                                         const board::BoardToProjector& mapping, double thickness_px);

class ProblemOutline {
 public:
  // The same rule as the session's instruction (ProjectionNode::kStudySessionHeardUs): the driver sends
  // once a second, three missed messages mean it has gone.
  static constexpr int64_t kHeardUs = 3'000'000;

  // The newest problem heard at `now` (bus clock). Returns "" when taken, or why it was refused
  // (problem_fault); a refused problem also drops the one before it: the newest wins, and what the
  // driver now asks is not known.
  std::string take(const study_problem_t& problem, int64_t now);
  // What to show at `now`. session: the newest study_session_t, heard at session_utime (nullptr: none).
  // A score problem's time left is the session's step_remaining_ms, counted down on the bus clock since
  // that session message while its step runs: the session's clock stands still while paused, and a
  // projection started mid-problem shows the time really left.
  ProblemView view(int64_t now, const study_session_t* session, int64_t session_utime) const;

  const study_problem_t* problem() const { return problem_ ? &*problem_ : nullptr; }

 private:
  std::optional<study_problem_t> problem_;
  int64_t heard_utime_ = 0;
};

}  // namespace bricklayer::projection
