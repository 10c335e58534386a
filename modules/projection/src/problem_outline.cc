#include "bricklayer/projection/problem_outline.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace bricklayer::projection {

namespace {

using S = study_session_t;
using P = study_problem_t;

double distance(board::Point2 a, board::Point2 b) { return std::hypot(a.x - b.x, a.y - b.y); }

// The width in board units that spans `px` projector pixels along a mapped segment `units` long (0 when
// the mapping degenerates there, so the ring shrinks to the edge instead of spreading).
double board_span(board::Point2 a, board::Point2 b, double units, double px) {
  const double pixels_per_unit = distance(a, b) / units;
  if (!std::isfinite(pixels_per_unit) || pixels_per_unit <= 0) return 0;
  return px / pixels_per_unit;
}

}  // namespace

std::string problem_fault(const P& p) {
  if (p.num_blocks != static_cast<int32_t>(p.blocks.size()))
    return "num_blocks " + std::to_string(p.num_blocks) + " disagrees with its " + std::to_string(p.blocks.size()) +
           " blocks";
  if (p.problem < 1 || p.problem > 3) return "problem " + std::to_string(p.problem) + " is not 1, 2 or 3";
  if (p.time_limit_ms < 0) return "negative time limit " + std::to_string(p.time_limit_ms) + " ms";
  if (p.kind == P::KIND_STABILISE) {
    if (p.blocks.empty()) return "a stabilise problem without blocks";
    if (p.num_blocks > kMaxProblemBlocks)
      return std::to_string(p.num_blocks) + " blocks (at most " + std::to_string(kMaxProblemBlocks) + ")";
    for (const block_t& b : p.blocks) {
      if (!std::isfinite(b.x) || std::abs(b.x) > kMaxProblemX)
        return "block " + std::to_string(b.id) + " has x " + std::to_string(b.x);
      if (b.row < 0 || b.row > kMaxProblemRow)
        return "block " + std::to_string(b.id) + " has row " + std::to_string(b.row) + " (0.." +
               std::to_string(kMaxProblemRow) + ")";
    }
    return "";
  }
  if (p.kind == P::KIND_SCORE) {
    if (p.min_score < 0) return "negative min_score " + std::to_string(p.min_score);
    if (p.max_blocks < 1 || p.max_blocks > kMaxProblemBlocks)
      return "max_blocks " + std::to_string(p.max_blocks) + " (1.." + std::to_string(kMaxProblemBlocks) + ")";
    return "";
  }
  return "unknown kind " + std::to_string(p.kind);
}

std::string score_target_text(int min_score, int max_blocks, std::optional<int64_t> remaining_ms) {
  std::string text = "TARGET " + std::to_string(min_score) + " points with at most " + std::to_string(max_blocks) +
                     (max_blocks == 1 ? " block" : " blocks");
  if (remaining_ms) {
    // Whole seconds rounded up, as the round timer counts: "0:00" only once the time is up.
    const int64_t seconds = (std::max<int64_t>(*remaining_ms, 0) + 999) / 1000;
    char buffer[48];
    std::snprintf(buffer, sizeof(buffer), " - %lld:%02lld left", static_cast<long long>(seconds / 60),
                  static_cast<long long>(seconds % 60));
    text += buffer;
  }
  return text;
}

std::array<std::array<board::Point2, 4>, 4> outline_ring(const ProblemBlock& block, double block_height,
                                                         const board::BoardToProjector& mapping, double thickness_px) {
  const double x0 = block.x, x1 = block.x + 1;
  const double y0 = block.row * block_height, y1 = y0 + block_height;
  // The thickness in board units at this block (the mapping is a homography: its scale varies over the board).
  const double dx = std::min(0.5, board_span(mapping.map(x0, y0), mapping.map(x1, y0), 1.0, thickness_px));
  const double dy =
      std::min(block_height / 2, board_span(mapping.map(x0, y0), mapping.map(x0, y1), block_height, thickness_px));
  const board::Point2 o[4] = {mapping.map(x0, y0), mapping.map(x1, y0), mapping.map(x1, y1), mapping.map(x0, y1)};
  const board::Point2 i[4] = {mapping.map(x0 + dx, y0 + dy), mapping.map(x1 - dx, y0 + dy),
                              mapping.map(x1 - dx, y1 - dy), mapping.map(x0 + dx, y1 - dy)};
  std::array<std::array<board::Point2, 4>, 4> sides{};
  for (int k = 0; k < 4; ++k) {
    const int n = (k + 1) % 4;
    sides[static_cast<size_t>(k)] = {o[k], o[n], i[n], i[k]};
  }
  return sides;
}

std::string ProblemOutline::take(const P& problem, int64_t now) {
  std::string fault = problem_fault(problem);
  if (!fault.empty()) {
    problem_.reset();
    return fault;
  }
  problem_ = problem;
  heard_utime_ = now;
  return "";
}

ProblemView ProblemOutline::view(int64_t now, const S* session, int64_t session_utime) const {
  ProblemView v;
  if (!problem_ || now - heard_utime_ > kHeardUs) return v;
  if (!session || now - session_utime > kHeardUs || session->session_id != problem_->session_id) return v;
  if (session->step != S::STEP_PROBLEM_1 + problem_->problem - 1) return v;
  if (session->state != S::STATE_RUNNING && session->state != S::STATE_PAUSED) return v;
  if (problem_->kind == P::KIND_STABILISE) {
    v.outlines.reserve(problem_->blocks.size());
    for (const block_t& b : problem_->blocks) v.outlines.push_back(ProblemBlock{b.row, b.x});
    return v;
  }
  std::optional<int64_t> remaining;
  if (problem_->time_limit_ms > 0) {
    const int64_t since_ms = session->state == S::STATE_RUNNING ? (now - session_utime) / 1000 : 0;
    remaining = std::clamp<int64_t>(session->step_remaining_ms - since_ms, 0, problem_->time_limit_ms);
  }
  v.target = score_target_text(problem_->min_score, problem_->max_blocks, remaining);
  return v;
}

}  // namespace bricklayer::projection
