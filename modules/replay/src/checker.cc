#include "bricklayer/replay/checker.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>

#include "bricklayer/common/channels.h"
#include "bricklayer/heartbeat_t.hpp"
#include "bricklayer/runtime/codec.h"

namespace bricklayer::replay {

std::vector<std::string> run_to_run_fields() {
  // timing_t: stage times measured with a stopwatch; heartbeat_t: uptime, counters, pid, status;
  // node_config_t: instance and time (and the replay's own overrides).
  return {"timing_t", "heartbeat_t", "node_config_t"};
}

void LoggerLosses::observe(const runtime::LogEvent& e) {
  static const std::string heartbeats = channel(kHeartbeatChannel);
  if (e.channel != heartbeats) return;
  const auto hb = runtime::decode<heartbeat_t>(e.data);
  if (!hb || hb->module != "logger") return;
  for (size_t i = 0; i < hb->value_names.size() && i < hb->values.size(); ++i) {
    if (hb->value_names[i] != "lost") continue;
    auto [it, fresh] = by_instance_.emplace(hb->instance, std::make_pair(hb->values[i], hb->values[i]));
    if (!fresh && hb->values[i] > it->second.second) {
      if (it->second.second == it->second.first && first_ == 0) first_ = e.utime;
      last_ = e.utime;
    }
    it->second.second = hb->values[i];
  }
}

int64_t LoggerLosses::lost() const {
  double n = 0;
  for (const auto& [instance, v] : by_instance_) n += v.second - v.first;
  return static_cast<int64_t>(n);
}

std::string Checker::when(int64_t utime, int64_t start) {
  const std::time_t t = static_cast<std::time_t>(utime / 1'000'000);
  std::tm tm{};
  localtime_r(&t, &tm);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%02d:%02d:%02d.%03d (+%.3f s)", tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>(utime % 1'000'000 / 1000), static_cast<double>(utime - start) / 1e6);
  return buf;
}

Checker::Checker(const MessageDiff& diff, std::ostream& out, int64_t start, size_t max_printed)
    : diff_(diff),
      out_(out),
      start_(start),
      max_printed_(max_printed),
      matcher_(
          diff,
          [this](const Pair& p) {
            const int64_t offset = p.b_stamp_utime - p.key.utime;
            const bool tick_stamped = std::find(nearest_channels_.begin(), nearest_channels_.end(), p.key.channel) !=
                                      nearest_channels_.end();
            // Stamped by a live clock: before the logger received it (on the rig, stamp = log time).
            const bool live_tick = tick_stamped && p.key.utime != p.a_log_utime;
            // Two ticks are fair to compare only when they had the same inputs. An input delivered
            // between them (a stack, a prediction, a command), or shortly before the earlier (the live
            // node may not have handled it yet: the logger heard it first), was seen by one and maybe
            // not the other, so their pictures and rounds may differ rightly. Counted, not compared.
            if (live_tick) {
              const int64_t lo = std::min(p.key.utime, p.b_stamp_utime) - kInputInFlightUs;
              const int64_t hi = std::max(p.key.utime, p.b_stamp_utime);
              const auto it = std::upper_bound(input_utimes_.begin(), input_utimes_.end(), lo);
              if (it != input_utimes_.end() && *it <= hi) {
                ++counts_.inputs_between;
                ++counts_.inputs_between_by_channel[p.key.channel];
                return;
              }
            }
            ++counts_.compared;
            ++counts_.compared_by_channel[p.key.channel];
            if (p.nearest) {
              ++counts_.nearest;
              ++counts_.nearest_by_channel[p.key.channel];
              counts_.worst_nearest_offset_us = std::max<int64_t>(counts_.worst_nearest_offset_us, std::llabs(offset));
            }
            if (p.a == p.b) return;
            // Stamped by a live tick, what depends on when the tick fell is left out of every pair: a
            // pair by key too has its round started at another tick (remaining_ms).
            const MessageDiff& compare = live_tick && tick_diff_ ? *tick_diff_ : diff_;
            const auto d = compare.differences(p.a, p.b);
            if (d.empty()) return;  // only run-to-run (or, paired by nearest time, tick-dependent) fields differ
            ++counts_.mismatches;
            ++counts_.mismatches_by_channel[p.key.channel];
            char by[96] = "";
            if (p.nearest)
              std::snprintf(by, sizeof by, " (paired by nearest time: the replayed one stamped %+.1f ms)",
                            static_cast<double>(offset) / 1000.0);
            const std::string line = p.key.channel + " (" + diff_.type_of(p.a.data(), p.a.size()) + ") at " +
                                     when(p.key.utime, start_) +
                                     (p.key.frame_number >= 0 ? " frame " + std::to_string(p.key.frame_number) : "") +
                                     by + ": " + MessageDiff::describe(d, "log", "replay");
            if (first_.empty()) first_ = line;
            if (counts_.mismatches <= static_cast<int64_t>(max_printed_)) out_ << "MISMATCH " << line << "\n";
          },
          [this](const MessageKey& key, int side) {
            ++(side == 0 ? counts_.orphans : counts_.not_in_log);
            if (std::find(nearest_channels_.begin(), nearest_channels_.end(), key.channel) != nearest_channels_.end())
              ++counts_.tick_unpaired[side];
          }) {}

void Checker::set_nearest(const std::vector<std::string>& channels, int64_t tolerance_us, const MessageDiff& tick_diff,
                          const std::vector<std::string>& input_channels) {
  tick_diff_ = &tick_diff;
  nearest_channels_ = channels;
  input_channels_ = input_channels;
  // Outputs whose contents agree pair first (two round_t 1 ms apart, one a change the other tick did
  // not make yet); one that differs still pairs, and is a mismatch.
  matcher_.set_nearest(channels, tolerance_us, 1'000'000, [&tick_diff](const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
    return tick_diff.differences(a, b).empty();
  });
}

void Checker::observe(const runtime::LogEvent& e) {
  losses_.observe(e);
  if (std::find(input_channels_.begin(), input_channels_.end(), e.channel) == input_channels_.end()) return;
  if (input_utimes_.empty() || e.utime >= input_utimes_.back()) input_utimes_.push_back(e.utime);
  // Pairs are decided within seconds of their stamps: older inputs are not needed.
  while (!input_utimes_.empty() && input_utimes_.front() < e.utime - 30'000'000) input_utimes_.pop_front();
}

void Checker::recorded(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
  matcher_.add(0, channel, bytes, utime);
  matcher_.advance(utime);
}

void Checker::replayed(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
  matcher_.add(1, channel, bytes, utime);
}

void Checker::finish() { matcher_.finish(); }

std::vector<std::string> damage_report(const RecordingReader& reader, int64_t from, int64_t to,
                                       const LoggerLosses* logger_losses) {
  std::vector<std::string> out;
  for (const auto& d : reader.damage())
    out.push_back(d.part + ": " + d.damage.describe() + "; " + std::to_string(d.events_after) +
                  " intact events after it were read and replayed");
  for (const auto& p : reader.missing_parts()) out.push_back(p + ": named by the index but gone (deleted by the disk budget?)");
  if (reader.index())
    for (const auto& l : reader.index()->losses())
      if (l.to_utime >= from && l.from_utime <= to)
        out.push_back("the logger could not keep " + std::to_string(l.events) + " events from " +
                      Checker::when(l.from_utime, from) + " to " + Checker::when(l.to_utime, from) + " (" + l.reason + ")");
  if (logger_losses && logger_losses->lost() > 0 && !reader.index())
    out.push_back("the logger's heartbeats report " + std::to_string(logger_losses->lost()) +
                  " events it could not keep (disk full or over budget), between " +
                  Checker::when(logger_losses->first_utime(), from) + " and " + Checker::when(logger_losses->last_utime(), from));
  return out;
}

}  // namespace bricklayer::replay
