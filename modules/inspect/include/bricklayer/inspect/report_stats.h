// What bricklayer-report shows, gathered in one pass over the log in bounded memory: per-round,
// per-episode, per-module and per-channel records, and time series in at most kMaxBins bins whose
// width doubles (1 s, 2 s, 4 s, ...) whenever the log outgrows them, so a day's log and a minute's
// both give readable plots without knowing the span in advance.
//
// Definitions (the README states them for the reader of the report):
// - a round runs from the first round_t in state RUNNING to the first one that is not (ENDED: "time
//   up", IDLE: "reset") or to the end of the log ("log ended"), or restarts when its time left jumps
//   up; its MAX is the last max_score seen while it ran;
// - a red episode runs from the first prediction_t (status OK) with a cause block to the first one
//   with none; it "fell" when that pile has fewer blocks than the one that turned red;
// - end-to-end latency: camera capture (the stack's utime) to the projector frame presented, from the
//   projection's "present" timing_t (received_utime + elapsed_us - utime), rounded down to 10 us;
// - a restart is a module's heartbeat from a new instance (host:pid) after its first one; errors are
//   the increments of every instance's error counter;
// - disk use: every event's bytes in the log file (28-byte header, channel name, message);
// - study sessions: their study_session_t, study_trial_t and study_answer_t messages, gathered by the
//   study module's own collector (bricklayer/study/table.h), which makes the seed paper's Table 1.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/inspect/decoded_log.h"
#include "bricklayer/inspect/value_counts.h"
#include "bricklayer/study/table.h"

namespace bricklayer::inspect {

inline constexpr size_t kMaxBins = 240;
inline constexpr int64_t kLatencyResolutionUs = 10;

struct RoundRecord {
  int64_t start_us = 0;  // utime of the first RUNNING round_t
  int64_t end_us = 0;    // utime of the last round_t of the round
  int32_t max_score = 0;
  int32_t blocks = 0;    // blocks in the pile at the end
  std::string ended;     // "time up", "reset", "restarted", "log ended"
};

struct RedEpisode {
  int64_t start_us = 0;  // utime of the first red prediction
  int64_t end_us = 0;    // utime of the first prediction without a cause (= start when the log ends red)
  int32_t blocks_red = 0;
  int32_t blocks_after = 0;
  bool fell = false;
  bool open = false;     // the log ended while red
};

struct ModuleRecord {
  uint64_t heartbeats = 0;
  uint64_t restarts_seen = 0;       // instances after the first
  int32_t launcher_restarts = 0;    // the largest "restarts" a heartbeat carried
  uint64_t errors = 0;
  uint64_t dropped = 0;
  std::string last_status;
  std::map<std::string, std::pair<int64_t, int64_t>> last_counters;  // instance -> (errors, dropped)
};

struct ChannelRecord {
  std::string type;  // full type name, "" when not decoded
  uint64_t messages = 0;
  uint64_t bytes = 0;
  int64_t first_us = 0;
  int64_t last_us = 0;
};

struct TimeBin {
  std::map<std::string, uint64_t> messages;  // per channel
  uint64_t bytes = 0;
  ValueCounts latency_us;
  uint64_t red_started = 0;
  uint64_t fell = 0;
  uint64_t errors = 0;
  uint64_t restarts = 0;
  void merge(const TimeBin& other);
};

class ReportStats {
 public:
  void add(const DecodedEvent& e);
  void finish();  // closes an open round or red episode at the end of the log

  int64_t first_us() const { return first_us_; }
  int64_t last_us() const { return last_us_; }
  uint64_t events() const { return events_; }
  int64_t bin_origin_us() const { return origin_us_; }
  int64_t bin_width_us() const { return width_us_; }
  const std::vector<TimeBin>& bins() const { return bins_; }
  const std::vector<RoundRecord>& rounds() const { return rounds_; }
  const std::vector<RedEpisode>& red_episodes() const { return episodes_; }
  const std::map<std::string, ModuleRecord>& modules() const { return modules_; }
  const std::map<std::string, ChannelRecord>& channels() const { return channels_; }
  const ValueCounts& latency_us() const { return latency_; }
  // Per (module, stage) of timing_t: elapsed_us as measured (exact microseconds).
  const std::map<std::pair<std::string, std::string>, ValueCounts>& stage_elapsed_us() const { return stages_; }
  // Study messages seen (session, trial, answer); 0 when the log holds no study session.
  uint64_t study_messages() const { return study_messages_; }
  const study::StudyCollector& study() const { return study_; }

 private:
  TimeBin& bin_at(int64_t t_us);
  void on_round(const Json& m);
  void on_prediction(const Json& m, int64_t t_us);
  void on_heartbeat(const Json& m, int64_t t_us);
  void on_timing(const Json& m, int64_t t_us);
  void on_study(const std::string& type, const std::vector<uint8_t>& data);

  uint64_t events_ = 0;
  int64_t first_us_ = 0, last_us_ = 0;
  int64_t origin_us_ = 0, width_us_ = 1000000;
  std::vector<TimeBin> bins_;
  std::vector<RoundRecord> rounds_;
  std::optional<RoundRecord> open_round_;
  int64_t last_remaining_ms_ = 0;
  std::vector<RedEpisode> episodes_;
  std::optional<RedEpisode> open_episode_;
  std::map<std::string, ModuleRecord> modules_;
  std::map<std::string, ChannelRecord> channels_;
  ValueCounts latency_;
  std::map<std::pair<std::string, std::string>, ValueCounts> stages_;
  uint64_t study_messages_ = 0;
  study::StudyCollector study_;
};

}  // namespace bricklayer::inspect
