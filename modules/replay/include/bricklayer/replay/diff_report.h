// --diff: two replays of the same log (other settings, or another build's program) compared output by
// output. What it reports:
//   counts         outputs of each side, pairs, identical, differing, outputs of one side only;
//   fields         per channel, how many messages differ in each field (blocks[].state: 34);
//   verdicts       for predictions: the block-state changes A -> B (stable, moving, cause) and the
//                  frames where they happen, with their times (the paper and exact annotators' known
//                  disagreements show up here);
//   blocks         for stacks: blocks only one side saw, and blocks moved or put in another row;
//   first          the first divergences, with their times.
#pragma once

#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "bricklayer/replay/message_diff.h"
#include "bricklayer/replay/output_matcher.h"

namespace bricklayer::replay {

class DiffReport {
 public:
  DiffReport(const MessageDiff& diff, std::string a_name, std::string b_name, int64_t start_utime,
             size_t max_listed = 10);

  void add(int side, const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime);
  void advance(int64_t utime) { matcher_.advance(utime); }
  void finish() { matcher_.finish(); }

  void print(std::ostream& out) const;
  int64_t differing() const { return differing_; }
  int64_t only(int side) const { return only_[side]; }
  int64_t pairs() const { return pairs_; }
  // Block-state changes A -> B: (from, to) -> count, states as in block_prediction_t.
  const std::map<std::pair<int, int>, int64_t>& verdict_changes() const { return verdict_changes_; }
  const std::vector<std::string>& verdict_frames() const { return verdict_frames_; }

 private:
  void pair(const Pair& p);
  void predictions(const Pair& p);
  void stacks(const Pair& p);

  const MessageDiff& diff_;
  std::string a_, b_;
  int64_t start_;
  size_t max_listed_;
  OutputMatcher matcher_;
  int64_t outputs_[2] = {0, 0}, only_[2] = {0, 0};
  int64_t pairs_ = 0, differing_ = 0;
  std::map<std::string, std::map<std::string, int64_t>> fields_;  // channel -> generic path -> messages
  std::map<std::string, std::pair<int64_t, int64_t>> per_channel_;  // channel -> (pairs, differing)
  std::vector<std::string> first_;
  std::map<std::pair<int, int>, int64_t> verdict_changes_;
  std::vector<std::string> verdict_frames_;
  int64_t balanced_flips_ = 0, verdict_messages_ = 0;
  int64_t blocks_only_[2] = {0, 0}, blocks_moved_ = 0, blocks_row_ = 0, block_messages_ = 0;
  std::vector<std::string> block_frames_;
};

}  // namespace bricklayer::replay
