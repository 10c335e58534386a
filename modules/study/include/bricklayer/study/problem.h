// A study problem, as read from a problem file (launch/problems/*.json; format in modules/study/README.md).
//
// Two kinds. "stabilise": the subject builds a given pile that falls and makes it stand by adding as few
// blocks as possible, without moving the given ones. "score": the subject reaches a score with at most a
// given number of blocks within a time limit. Every key is checked: an unknown or misspelt key is an
// error, never silently ignored.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "bricklayer/core/stack.h"
#include "bricklayer/study/placement.h"

namespace bricklayer::study {

enum class ProblemKind { kStabilise = 1, kScore = 2 };  // same values as study_problem_t::KIND_*

class ProblemError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Problem {
  std::string name;
  ProblemKind kind = ProblemKind::kStabilise;
  std::string description;  // for the experimenter and the reader of the file
  std::string instruction;  // what the display tells the subject
  int64_t time_limit_ms = 0;  // 0 = no limit

  // kStabilise
  core::Stack pile;  // normalised: block lengths, surface edge at x = 0
  int32_t minimum_added = -1;  // as declared in the file; the checker recomputes it (StabiliseChecker)
  std::vector<Placement> solution;  // one answer with minimum_added blocks, as declared
  double position_tolerance = 0.005;  // block lengths: how answers (measured piles) are judged
  double match_tolerance = 0.05;  // block lengths: a given block counts as in place within this of its position
  int32_t max_added = 2;  // the minimum is searched up to this many blocks

  // kScore
  int32_t min_score = 0;   // points (100 per block length of overhang)
  int32_t max_blocks = 0;  // at most this many blocks in the pile
  int64_t hold_ms = 1000;  // the goal counts once it has held this long (a pile must stand, not pass through)
};

// Parses a problem file's text. `fallback_name` is used when the file has no "name". Throws ProblemError
// (a one-line message naming the key) for anything malformed, including an invalid pile.
Problem parse_problem(std::string_view text, const std::string& fallback_name = "problem");
Problem load_problem(const std::string& path);  // name defaults to the file's stem

std::string to_string(ProblemKind kind);

}  // namespace bricklayer::study
