#include "bricklayer/inspect/report_numbers.h"

#include <algorithm>
#include <cmath>

#include "bricklayer/inspect/wall_clock.h"

namespace bricklayer::inspect {

namespace {

Json percentiles(const ValueCounts& v) {
  if (v.empty()) return Json{{"samples", 0}};
  return Json{{"samples", v.size()}, {"p50", v.percentile(50)}, {"p90", v.percentile(90)}, {"p99", v.percentile(99)}, {"max", v.max()}};
}

}  // namespace

Json report_numbers(const ReportStats& s, const ReadSummary& read, const std::vector<std::string>& logs) {
  Json out = Json::object();
  out["logs"] = logs;
  out["events"] = s.events();
  out["first_log_utime_us"] = s.first_us();
  out["last_log_utime_us"] = s.last_us();
  out["first_utc"] = utc_text(s.first_us());
  out["last_utc"] = utc_text(s.last_us());
  const double span_s = static_cast<double>(s.last_us() - s.first_us()) / 1e6;
  out["span_s"] = span_s;
  out["decoded"] = read.decoded;
  out["unknown_type"] = read.unknown_type;
  out["malformed"] = read.malformed;
  Json damage = Json::array();
  for (const auto& p : read.problems) damage.push_back({{"file", p.file}, {"offset", p.offset}, {"truncated", p.truncated}, {"what", p.what}});
  out["damage"] = damage;

  Json rounds = Json::array();
  ValueCounts maxima;
  for (const auto& r : s.rounds()) {
    rounds.push_back({{"start_utime_us", r.start_us}, {"start_utc", utc_text(r.start_us)}, {"end_utime_us", r.end_us},
                      {"end_utc", utc_text(r.end_us)}, {"duration_s", static_cast<double>(r.end_us - r.start_us) / 1e6},
                      {"max_score_points", r.max_score}, {"num_blocks", r.blocks}, {"ended", r.ended}});
    maxima.add(r.max_score);
  }
  out["rounds"] = rounds;
  Json rs = {{"count", s.rounds().size()}};
  if (!maxima.empty()) {
    rs["best_max_points"] = maxima.max();
    rs["median_max_points"] = maxima.percentile(50);
  }
  out["rounds_summary"] = rs;

  Json episodes = Json::array();
  ValueCounts durations;
  uint64_t fell = 0, open = 0;
  for (const auto& e : s.red_episodes()) {
    episodes.push_back({{"start_utime_us", e.start_us}, {"start_utc", utc_text(e.start_us)}, {"end_utime_us", e.end_us},
                        {"duration_us", e.end_us - e.start_us}, {"blocks_red", e.blocks_red},
                        {"blocks_after", e.blocks_after}, {"fell", e.fell}, {"open", e.open}});
    if (e.open) {
      ++open;
    } else {
      durations.add(e.end_us - e.start_us);
      if (e.fell) ++fell;
    }
  }
  out["red_episodes"] = episodes;
  Json red = {{"episodes", s.red_episodes().size()}, {"fell", fell}, {"open", open},
              {"fixed", s.red_episodes().size() - fell - open}, {"duration_us", percentiles(durations)}};
  red["fell_per_hour"] = span_s > 0 ? static_cast<double>(fell) * 3600.0 / span_s : 0.0;
  out["red_summary"] = red;

  out["latency_us"] = percentiles(s.latency_us());
  out["latency_us"]["resolution_us"] = kLatencyResolutionUs;
  Json stages = Json::array();
  for (const auto& [key, v] : s.stage_elapsed_us()) {
    Json st = percentiles(v);
    st["module"] = key.first;
    st["stage"] = key.second;
    stages.push_back(st);
  }
  out["stages_elapsed_us"] = stages;

  Json channels = Json::array();
  uint64_t total_bytes = 0;
  for (const auto& [name, c] : s.channels()) total_bytes += c.bytes;
  for (const auto& [name, c] : s.channels())
    channels.push_back({{"channel", name}, {"type", c.type}, {"messages", c.messages}, {"bytes", c.bytes},
                        {"rate_hz", span_s > 0 ? static_cast<double>(c.messages) / span_s : 0.0},
                        {"share", total_bytes ? static_cast<double>(c.bytes) / static_cast<double>(total_bytes) : 0.0}});
  out["channels"] = channels;
  out["disk"] = {{"bytes", total_bytes}, {"mb_per_hour", span_s > 0 ? static_cast<double>(total_bytes) / 1e6 * 3600.0 / span_s : 0.0}};

  Json modules = Json::array();
  for (const auto& [name, m] : s.modules())
    modules.push_back({{"module", name}, {"heartbeats", m.heartbeats}, {"restarts_seen", m.restarts_seen},
                       {"launcher_restarts", m.launcher_restarts}, {"errors", m.errors}, {"dropped", m.dropped},
                       {"last_status", m.last_status}});
  out["modules"] = modules;
  if (s.study_messages() > 0) {
    const auto sessions = s.study().sessions();
    const study::StudyTable table = study::make_table(sessions);
    auto number = [](double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); };
    Json rows = Json::array();
    for (const auto& r : table.rows)
      rows.push_back({{"condition", study::to_string(r.condition)}, {"subjects", r.subjects},
                      {"trial1_mean_points", number(r.trial1_mean)}, {"solved", r.solved}, {"excess", r.excess},
                      {"trial2_mean_points", number(r.trial2_mean)}, {"ratio_n", r.ratio.n},
                      {"ratio_mean", number(r.ratio.mean)}, {"ratio_variance", number(r.ratio.variance)}});
    Json pairs = Json::array();
    for (const auto& p : table.pairs)
      pairs.push_back({{"a", study::to_string(p.a)}, {"b", study::to_string(p.b)}, {"f", number(p.f.f)},
                       {"f_p", number(p.f.p)}, {"f_valid", p.f.valid}, {"t", number(p.t.t)}, {"t_df", number(p.t.df)},
                       {"t_p", number(p.t.p)}, {"t_pooled", p.t.equal_variance}, {"t_valid", p.t.valid},
                       {"welch_p", number(p.welch.p)}});
    out["study"] = {{"messages", s.study_messages()}, {"sessions", sessions.size()}, {"rows", rows},
                    {"pairs", pairs}, {"excluded", table.excluded}, {"problems", s.study().problems()}};
  }
  out["bins"] = {{"origin_utime_us", s.bin_origin_us()}, {"width_s", static_cast<double>(s.bin_width_us()) / 1e6},
                 {"count", s.bins().size()}};
  return out;
}

}  // namespace bricklayer::inspect
