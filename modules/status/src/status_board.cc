#include "bricklayer/status/status_board.h"

#include "bricklayer/study_session_t.hpp"

#include <algorithm>
#include <cmath>

namespace bricklayer::status {

namespace {
constexpr int64_t kUsPerDay = 86'400'000'000LL;

std::string seconds_words(int64_t us) {
  const int64_t s = std::max<int64_t>(0, us / 1'000'000);
  if (s < 120) return std::to_string(s) + " s";
  if (s < 7200) return std::to_string(s / 60) + " min";
  return std::to_string(s / 3600) + " h " + std::to_string(s / 60 % 60) + " min";
}
}  // namespace

const char* level_name(Level level) {
  switch (level) {
    case Level::ok: return "ok";
    case Level::warning: return "warning";
    case Level::failed: return "failed";
  }
  return "failed";
}

const char* state_name(int8_t state) {
  switch (state) {
    case module_state_t::STATE_WAITING: return "waiting";
    case module_state_t::STATE_STARTING: return "starting";
    case module_state_t::STATE_UP: return "up";
    case module_state_t::STATE_RESTARTING: return "restarting";
    case module_state_t::STATE_FAILED: return "failed";
    case module_state_t::STATE_EXITED: return "finished";
    case module_state_t::STATE_STOPPED: return "stopped";
  }
  return "unknown";
}

ModuleReading read_module(const module_state_t& m) {
  const std::string how = m.last_exit.empty() ? "" : " (it ended: " + m.last_exit + ")";
  switch (m.state) {
    case module_state_t::STATE_UP:
      // Up, but the module itself says what is wrong: its words are meant for the operator.
      if (!m.status.empty() && m.status != "ok") return {Level::warning, m.status};
      return {};
    case module_state_t::STATE_EXITED: return {};
    case module_state_t::STATE_WAITING: return {Level::warning, "not started yet, waiting for the modules before it"};
    case module_state_t::STATE_STARTING: return {Level::warning, "starting"};
    case module_state_t::STATE_RESTARTING:
      return {Level::warning, "restarting" + how + (m.restarts > 0 ? ", restarted " + std::to_string(m.restarts) + " times" : "")};
    case module_state_t::STATE_FAILED:
      return {Level::failed, "stopped for good" + how + "; it will not restart by itself"};
    case module_state_t::STATE_STOPPED: return {Level::warning, "stopped (the exhibit is shutting down)"};
  }
  return {Level::failed, "in an unknown state " + std::to_string(m.state)};
}

StatusBoard::StatusBoard(double silent_after_s) : silent_after_s_(silent_after_s) {}

void StatusBoard::set_now(int64_t utime) {
  std::lock_guard lock(mutex_);
  now_ = utime;
}

void StatusBoard::update(const host_state_t& state, int64_t received_utime) {
  std::lock_guard lock(mutex_);
  Host& h = hosts_[state.host];
  h.state = state;
  h.received_utime = received_utime;
  now_ = std::max(now_, received_utime);
}

void StatusBoard::update(const round_t& round) {
  std::lock_guard lock(mutex_);
  round_ = round;
  const int64_t day = round.utime / kUsPerDay;
  if (day != best_day_) {
    best_day_ = day;
    best_today_ = 0;
  }
  best_today_ = std::max(best_today_, round.max_score);
}

void StatusBoard::update(const heartbeat_t& hb) {
  std::lock_guard lock(mutex_);
  if (hb.pid <= 0 || hb.module == "launcher") return;
  Figures& f = figures_[hb.pid];
  f.received_utime = now_;
  f.module = hb.module;
  const size_t n = std::min({static_cast<size_t>(std::max(0, hb.num_values)), hb.value_names.size(), hb.values.size()});
  f.names.assign(hb.value_names.begin(), hb.value_names.begin() + static_cast<std::ptrdiff_t>(n));
  f.values.assign(hb.values.begin(), hb.values.begin() + static_cast<std::ptrdiff_t>(n));
  // A one-off bricklayer-calibrate run (at the board) is "calibrate" too: the line follows the serving one.
  if (hb.module == "calibrate" && std::find(f.names.begin(), f.names.end(), "calibrations_done") != f.names.end()) {
    Calibrate c;
    c.received_utime = now_;
    c.status = hb.status;
    c.figures = nlohmann::json::object();
    for (size_t i = 0; i < n; ++i)
      if (std::isfinite(f.values[i])) c.figures[f.names[i]] = f.values[i];
    calibrate_ = std::move(c);
  }
  for (auto it = figures_.begin(); it != figures_.end();)
    it = now_ - it->second.received_utime > 60'000'000 ? figures_.erase(it) : std::next(it);
}

size_t StatusBoard::num_hosts() const {
  std::lock_guard lock(mutex_);
  return hosts_.size();
}

nlohmann::json StatusBoard::figures_of(int32_t pid) const {
  nlohmann::json out = nlohmann::json::object();
  const auto it = pid > 0 ? figures_.find(pid) : figures_.end();
  if (it == figures_.end()) return out;
  for (size_t i = 0; i < it->second.names.size(); ++i)
    if (std::isfinite(it->second.values[i])) out[it->second.names[i]] = it->second.values[i];
  return out;
}

nlohmann::json StatusBoard::to_json() const {
  std::lock_guard lock(mutex_);
  using nlohmann::json;
  Level worst = Level::ok;
  json problems = json::array();
  json hosts = json::array();
  for (const auto& [name, h] : hosts_) {
    const host_state_t& s = h.state;
    const int64_t age = now_ - h.received_utime;
    const bool silent = age > static_cast<int64_t>(silent_after_s_ * 1e6);
    Level host_level = Level::ok;
    json modules = json::array();
    for (const module_state_t& m : s.modules) {
      ModuleReading r = read_module(m);
      // A silent host's module states are old news: shown, but the host's silence is the problem.
      if (r.level != Level::ok && !silent) problems.push_back(m.name + ": " + r.words);
      host_level = std::max(host_level, r.level);
      modules.push_back({{"name", m.name}, {"state", state_name(m.state)}, {"level", level_name(r.level)},
                         {"words", r.words}, {"pid", m.pid}, {"restarts", m.restarts},
                         {"uptime_s", static_cast<double>(m.uptime_us) / 1e6}, {"status", m.status},
                         {"last_exit", m.last_exit}, {"received", m.received}, {"published", m.published},
                         {"dropped", m.dropped}, {"errors", m.errors}, {"figures", figures_of(m.pid)}});
    }
    if (silent) {
      host_level = Level::failed;
      problems.push_back(name + " is silent: nothing heard from it for " + seconds_words(age) +
                         " (the machine is off, its exhibit is not running, or the network cable is out)");
    }
    worst = std::max(worst, host_level);
    hosts.push_back({{"host", name}, {"profile", s.profile}, {"launcher_pid", s.launcher_pid},
                     {"uptime_s", static_cast<double>(s.uptime_us) / 1e6}, {"modules_up", s.modules_up},
                     {"num_modules", s.num_modules}, {"status", s.status}, {"silent", silent},
                     {"age_s", static_cast<double>(age) / 1e6}, {"level", level_name(host_level)},
                     {"modules", modules}});
  }
  if (hosts_.empty()) {
    worst = Level::failed;
    problems.push_back("no machine heard from yet: the exhibit is not running, or this page listens on another network");
  }
  // The display condition's word as the page's control names it (study_session_t::CONDITION_* values).
  auto condition_word = [](int8_t c) -> const char* {
    return c == study_session_t::CONDITION_BLUE       ? "blue"
           : c == study_session_t::CONDITION_RED      ? "red"
           : c == study_session_t::CONDITION_PROPOSED ? "proposed"
                                                      : "unknown";
  };
  json round = nullptr;
  if (round_) {
    const round_t& r = *round_;
    const char* state = r.state == round_t::STATE_RUNNING ? "running" : r.state == round_t::STATE_ENDED ? "ended" : "idle";
    round = {{"state", state}, {"remaining_s", static_cast<double>(r.remaining_ms) / 1e3},
             {"duration_s", static_cast<double>(r.duration_ms) / 1e3}, {"score", r.score},
             {"max_score", r.max_score}, {"num_blocks", r.num_blocks},
             {"condition", condition_word(r.condition)}};
  }
  json calibration = nullptr;
  if (calibrate_)
    calibration = {{"status", calibrate_->status}, {"age_s", static_cast<double>(now_ - calibrate_->received_utime) / 1e6},
                   {"figures", calibrate_->figures}};
  return {{"utime", now_}, {"level", level_name(worst)}, {"problems", problems}, {"hosts", hosts},
          {"round", round}, {"best_today", best_today_}, {"calibration", calibration}};
}

}  // namespace bricklayer::status
