#include "bricklayer/inspect/report_stats.h"

namespace bricklayer::inspect {

namespace {

constexpr int8_t kRoundIdle = 0, kRoundRunning = 1, kRoundEnded = 2;  // round_t.STATE_*
constexpr int8_t kCause = 2;                                          // block_prediction_t.STATE_CAUSE
constexpr int8_t kPredictionOk = 0;                                   // prediction_t.STATUS_OK

}  // namespace

void TimeBin::merge(const TimeBin& o) {
  for (const auto& [c, n] : o.messages) messages[c] += n;
  bytes += o.bytes;
  latency_us.merge(o.latency_us);
  red_started += o.red_started;
  fell += o.fell;
  errors += o.errors;
  restarts += o.restarts;
}

TimeBin& ReportStats::bin_at(int64_t t) {
  if (bins_.empty()) origin_us_ = (t / 1000000) * 1000000;
  int64_t index = t < origin_us_ ? 0 : (t - origin_us_) / width_us_;
  while (index >= static_cast<int64_t>(kMaxBins)) {
    // Twice as wide: bins 2k and 2k+1 become bin k.
    std::vector<TimeBin> merged((bins_.size() + 1) / 2);
    for (size_t i = 0; i < bins_.size(); ++i) merged[i / 2].merge(bins_[i]);
    bins_ = std::move(merged);
    width_us_ *= 2;
    index = (t - origin_us_) / width_us_;
  }
  if (index >= static_cast<int64_t>(bins_.size())) bins_.resize(static_cast<size_t>(index) + 1);
  return bins_[static_cast<size_t>(index)];
}

void ReportStats::add(const DecodedEvent& e) {
  const int64_t t = e.event.timestamp_us;
  if (events_++ == 0) first_us_ = t;
  last_us_ = std::max(last_us_, t);
  const uint64_t bytes = 28 + e.event.channel.size() + e.event.data.size();
  TimeBin& bin = bin_at(t);
  bin.messages[e.event.channel]++;
  bin.bytes += bytes;
  ChannelRecord& c = channels_[e.event.channel];
  if (c.messages++ == 0) c.first_us = t;
  c.last_us = t;
  c.bytes += bytes;
  if (!e.message) return;
  if (c.type.empty()) c.type = e.type->full_name();
  const std::string& type = e.type->full_name();
  if (type == "bricklayer.round_t") on_round(*e.message);
  else if (type == "bricklayer.prediction_t") on_prediction(*e.message, t);
  else if (type == "bricklayer.heartbeat_t") on_heartbeat(*e.message, t);
  else if (type == "bricklayer.timing_t") on_timing(*e.message, t);
  else if (type == "bricklayer.study_session_t" || type == "bricklayer.study_trial_t" || type == "bricklayer.study_answer_t")
    on_study(type, e.event.data);
}

void ReportStats::on_study(const std::string& type, const std::vector<uint8_t>& data) {
  // The study module's collector takes its generated messages: decode the same bytes with them (the
  // generic decoder already accepted them, so this cannot fail unless the two disagree).
  auto decode = [&](auto& msg) {
    return msg.decode(data.data(), 0, static_cast<int>(data.size())) == static_cast<int>(data.size());
  };
  ++study_messages_;
  if (type == "bricklayer.study_session_t") {
    study_session_t m;
    if (decode(m)) study_.add(m);
  } else if (type == "bricklayer.study_trial_t") {
    study_trial_t m;
    if (decode(m)) study_.add(m);
  } else {
    study_answer_t m;
    if (decode(m)) study_.add(m);
  }
}

void ReportStats::on_round(const Json& m) {
  const int8_t state = m.at("state").get<int8_t>();
  const int64_t utime = m.at("utime").get<int64_t>();
  const int64_t remaining = m.at("remaining_ms").get<int64_t>();
  if (open_round_ && state == kRoundRunning && remaining > last_remaining_ms_) {
    open_round_->ended = "restarted";
    rounds_.push_back(*open_round_);
    open_round_.reset();
  }
  if (state == kRoundRunning) {
    if (!open_round_) {
      open_round_ = RoundRecord{};
      open_round_->start_us = utime;
    }
    open_round_->end_us = utime;
    open_round_->max_score = m.at("max_score").get<int32_t>();
    open_round_->blocks = m.at("num_blocks").get<int32_t>();
    last_remaining_ms_ = remaining;
  } else if (open_round_) {
    open_round_->end_us = utime;
    if (state == kRoundEnded) open_round_->max_score = m.at("max_score").get<int32_t>();
    open_round_->ended = state == kRoundEnded ? "time up" : state == kRoundIdle ? "reset" : "state " + std::to_string(state);
    rounds_.push_back(*open_round_);
    open_round_.reset();
  }
}

void ReportStats::on_prediction(const Json& m, int64_t t) {
  if (m.at("status").get<int8_t>() != kPredictionOk) return;
  bool red = false;
  for (const auto& b : m.at("blocks"))
    if (b.at("state").get<int8_t>() == kCause) red = true;
  const int64_t utime = m.at("utime").get<int64_t>();
  const int32_t blocks = m.at("num_blocks").get<int32_t>();
  if (red && !open_episode_) {
    open_episode_ = RedEpisode{};
    open_episode_->start_us = utime;
    open_episode_->end_us = utime;
    open_episode_->blocks_red = blocks;
    bin_at(t).red_started++;
  } else if (!red && open_episode_) {
    open_episode_->end_us = utime;
    open_episode_->blocks_after = blocks;
    open_episode_->fell = blocks < open_episode_->blocks_red;
    if (open_episode_->fell) bin_at(t).fell++;
    episodes_.push_back(*open_episode_);
    open_episode_.reset();
  }
}

void ReportStats::on_heartbeat(const Json& m, int64_t t) {
  const std::string name = m.at("module").get<std::string>();
  const std::string instance = m.at("instance").get<std::string>();
  ModuleRecord& r = modules_[name];
  r.heartbeats++;
  r.launcher_restarts = std::max(r.launcher_restarts, m.at("restarts").get<int32_t>());
  r.last_status = m.at("status").get<std::string>();
  const int64_t errors = m.at("errors").get<int64_t>();
  const int64_t dropped = m.at("dropped").get<int64_t>();
  auto it = r.last_counters.find(instance);
  if (it == r.last_counters.end()) {
    if (!r.last_counters.empty()) {
      r.restarts_seen++;
      bin_at(t).restarts++;
    }
    it = r.last_counters.emplace(instance, std::make_pair(int64_t{0}, int64_t{0})).first;
  }
  if (errors > it->second.first) {
    const uint64_t delta = static_cast<uint64_t>(errors - it->second.first);
    r.errors += delta;
    bin_at(t).errors += delta;
    it->second.first = errors;
  }
  if (dropped > it->second.second) {
    r.dropped += static_cast<uint64_t>(dropped - it->second.second);
    it->second.second = dropped;
  }
}

void ReportStats::on_timing(const Json& m, int64_t t) {
  const std::string module = m.at("module").get<std::string>();
  const std::string stage = m.at("stage").get<std::string>();
  const int64_t elapsed = m.at("elapsed_us").get<int64_t>();
  stages_[{module, stage}].add(elapsed);
  if (module == "projection" && stage == "present") {
    const int64_t e2e = m.at("received_utime").get<int64_t>() + elapsed - m.at("utime").get<int64_t>();
    if (e2e < 0) return;  // clocks of two hosts disagree: no latency to show
    const int64_t rounded = e2e / kLatencyResolutionUs * kLatencyResolutionUs;
    latency_.add(rounded);
    bin_at(t).latency_us.add(rounded);
  }
}

void ReportStats::finish() {
  if (open_round_) {
    open_round_->ended = "log ended";
    rounds_.push_back(*open_round_);
    open_round_.reset();
  }
  if (open_episode_) {
    open_episode_->open = true;
    episodes_.push_back(*open_episode_);
    open_episode_.reset();
  }
}

}  // namespace bricklayer::inspect
