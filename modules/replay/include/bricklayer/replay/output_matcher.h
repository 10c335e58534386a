// Pairs replayed outputs with recorded ones (or with another replay's) by the input they answer
// (channel + utime + frame_number), in bounded memory: the log is read in order and an output answers
// an input read shortly before it, so anything unpaired for longer than a window of log time is
// settled as unpaired. The same input answered twice (live: a module restarted) pairs with either.
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
};

}  // namespace bricklayer::replay
