// --check: every replayed output against the recorded one for the same input. What counts:
//   compared      pairs found; a pair whose compared fields differ is a mismatch, printed with its
//                 time and fields (the first one is the first divergence);
//   not in log    replayed outputs with no recorded one (live, a newer input replaced that one:
//                 newest wins), not a mismatch;
//   orphans       recorded outputs whose input is not in the range (a split or --from boundary);
//   damage        torn or truncated stretches of the log, parts of the recording that are gone, and
//                 events the logger could not keep (its heartbeat's "lost", the index's losses): the
//                 replay cannot vouch for what is missing, so the check fails.
// Run-to-run messages and fields (timings, heartbeats, configurations) are never compared; they are
// listed in the report.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "bricklayer/replay/message_diff.h"
#include "bricklayer/replay/output_matcher.h"
#include "bricklayer/replay/recording.h"
#include "bricklayer/runtime/log_file.h"

namespace bricklayer::replay {

// Run-to-run: never compared (the report lists them).
std::vector<std::string> run_to_run_fields();

struct CheckCounts {
  int64_t compared = 0, mismatches = 0, not_in_log = 0, orphans = 0;
  std::map<std::string, int64_t> mismatches_by_channel;
  std::map<std::string, int64_t> compared_by_channel;
  std::map<std::string, int64_t> nearest_by_channel;  // of compared: paired by nearest stamp time
  int64_t nearest = 0;
  int64_t worst_nearest_offset_us = 0;  // the largest |replayed stamp - recorded stamp| of those
  // Outputs on those channels that paired with nothing (recorded, replayed): no output of the other
  // side about the same input within the tolerance (a projector state whose stack the other side
  // showed only in a later or earlier state). Counted, not compared; also in orphans / not_in_log.
  int64_t tick_unpaired[2] = {0, 0};
  // Pairs of live-stamped outputs not compared: an input was delivered between their two stamps or
  // within kInputInFlightUs before the earlier.
  int64_t inputs_between = 0;
  std::map<std::string, int64_t> inputs_between_by_channel;
};

// Losses the logger itself reported in the log: the increase of its heartbeat's "lost" value.
class LoggerLosses {
 public:
  void observe(const runtime::LogEvent& e);
  int64_t lost() const;
  int64_t first_utime() const { return first_; }
  int64_t last_utime() const { return last_; }

 private:
  std::map<std::string, std::pair<double, double>> by_instance_;  // first and latest value
  int64_t first_ = 0, last_ = 0;
};

class Checker {
 public:
  // How long before a live tick an input the logger received may still be unhandled by the live node.
  static constexpr int64_t kInputInFlightUs = 10'000;

  // out: where mismatches are printed (at most max_printed, then counted only).
  Checker(const MessageDiff& diff, std::ostream& out, int64_t log_start_utime, size_t max_printed = 10);

  // Outputs stamped at a loop tick (output_matcher.h): on these channels, outputs unpaired by key pair
  // by nearest stamp time within tolerance_us, and every pair on them is compared with tick_diff (which
  // also leaves out the fields that depend on when the tick fell). tick_diff must outlive the checker.
  // input_channels: what the tick-stamped modules read; a pair by nearest time with an input delivered
  // between its two stamps is counted (inputs_between), not compared.
  void set_nearest(const std::vector<std::string>& channels, int64_t tolerance_us, const MessageDiff& tick_diff,
                   const std::vector<std::string>& input_channels = {});

  void recorded(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime);
  void replayed(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime);
  void observe(const runtime::LogEvent& e);
  void finish();

  const CheckCounts& counts() const { return counts_; }
  const std::string& first_divergence() const { return first_; }
  const LoggerLosses& losses() const { return losses_; }
  // "14:32:05.123 (+12.3 s)": a log time for people.
  static std::string when(int64_t utime, int64_t start_utime);

 private:
  const MessageDiff& diff_;
  const MessageDiff* tick_diff_ = nullptr;
  std::vector<std::string> nearest_channels_, input_channels_;
  std::deque<int64_t> input_utimes_;  // log times of the recent inputs, in order
  std::ostream& out_;
  int64_t start_;
  size_t max_printed_;
  CheckCounts counts_;
  std::string first_;
  LoggerLosses losses_;
  OutputMatcher matcher_;
};

// The damage lines of a recording (empty when it is whole): torn or truncated stretches, with how
// many events were read after each; parts gone; losses in the index within [from, to].
std::vector<std::string> damage_report(const RecordingReader& reader, int64_t from_utime, int64_t to_utime,
                                       const LoggerLosses* logger_losses);

}  // namespace bricklayer::replay
