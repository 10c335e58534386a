// Pairs replayed outputs with recorded ones (or with another replay's) by the input they answer
// (channel + utime + frame_number), in bounded memory: the log is read in order and an output answers
// an input read shortly before it, so anything unpaired for longer than a window of log time is
// settled as unpaired. The same input answered twice (live: a module restarted) pairs with either.
//
// Outputs stamped at a loop tick of their own (projection's round_t and projector states, calibrate's
// outputs) answer no input: on a log recorded live their stamps are the live node's ticks, which a
// replay does not repeat exactly. On the channels named as such (set_nearest), an output that found no
// pair by its key is paired with the other side's nearest one in stamp time (utime) about the same
// input (the same frame_number, where the type has one: the stack a projector state drew), within a
// tolerance: both sides' outputs aligned in the order they were stamped, at least cost (a pair costs
// its stamps' distance, plus the tolerance when their contents differ; an output left alone costs the
// tolerance: so an output whose content differs still pairs and is caught, unless an equal one of the
// other side is as near), decided only once everything within the tolerance of both has arrived. Such a pair says so (Pair::nearest), so its tick-dependent fields
// can be left out of the comparison.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "bricklayer/replay/message_diff.h"

namespace bricklayer::replay {

struct Pair {
  MessageKey key;
  int64_t utime = 0;  // log time of the later of the two
  std::vector<uint8_t> a, b;
  bool nearest = false;      // paired by nearest stamp time (key: side 0's), not by key
  int64_t b_stamp_utime = 0;  // side 1's stamp (its key's utime)
  int64_t a_log_utime = 0;    // when side 0's arrived (its log time)
};

class OutputMatcher {
 public:
  // on_pair(pair): both sides present. on_lone(key, side): only side 0 (a) or 1 (b) ever had it.
  OutputMatcher(const MessageDiff& diff, std::function<void(const Pair&)> on_pair,
                std::function<void(const MessageKey&, int side)> on_lone, int64_t window_us = 10'000'000);

  // side 0 or 1; bytes that have no key are reported to on_lone with an empty key channel.
  void add(int side, const std::string& channel, std::vector<uint8_t> bytes, int64_t log_utime);
  // Settles everything older than window behind log_utime.
  void advance(int64_t log_utime);
  void finish();  // settles everything
  // On these channels, outputs unpaired by key pair by nearest stamp time within tolerance_us.
  // arrival_us: how long after its stamp an output may still reach the matcher (log time vs stamp).
  // same(a, b): whether two outputs agree in what is compared (empty: by their bytes).
  void set_nearest(std::vector<std::string> channels, int64_t tolerance_us, int64_t arrival_us = 1'000'000,
                   std::function<bool(const std::vector<uint8_t>&, const std::vector<uint8_t>&)> same = {});
  int64_t nearest_tolerance_us() const { return tolerance_us_; }

 private:
  struct Waiting {
    std::vector<uint8_t> bytes;
    int64_t utime;
  };
  const MessageDiff& diff_;
  std::function<void(const Pair&)> on_pair_;
  std::function<void(const MessageKey&, int)> on_lone_;
  int64_t window_us_;
  std::map<MessageKey, std::deque<Waiting>> waiting_[2];
  std::deque<std::pair<int64_t, MessageKey>> order_[2];  // arrival order, for settling
  void pair_nearest(int64_t log_utime, bool everything);
  bool is_nearest(const std::string& channel) const;
  std::vector<std::string> nearest_channels_;
  int64_t tolerance_us_ = 0, arrival_us_ = 0;
  std::function<bool(const std::vector<uint8_t>&, const std::vector<uint8_t>&)> same_;
};

}  // namespace bricklayer::replay
