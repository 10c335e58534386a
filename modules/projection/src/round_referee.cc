#include "bricklayer/projection/round_referee.h"

#include <algorithm>
#include <ctime>
#include <stdexcept>

namespace bricklayer::projection {

const char* round_end_name(RoundEnd end) {
  switch (end) {
    case RoundEnd::kTimeUp: return "time up";
    case RoundEnd::kBoardCleared: return "board cleared";
    case RoundEnd::kRestarted: return "restarted";
    case RoundEnd::kReset: return "reset";
  }
  return "time up";
}

std::optional<RoundEnd> parse_round_end(const std::string& name) {
  for (RoundEnd e : {RoundEnd::kTimeUp, RoundEnd::kBoardCleared, RoundEnd::kRestarted, RoundEnd::kReset})
    if (name == round_end_name(e)) return e;
  return std::nullopt;
}

int local_day(int64_t utime) {
  const std::time_t seconds = static_cast<std::time_t>(utime / 1000000 - (utime % 1000000 < 0 ? 1 : 0));
  std::tm tm{};
  localtime_r(&seconds, &tm);
  return (tm.tm_year + 1900) * 10000 + (tm.tm_mon + 1) * 100 + tm.tm_mday;
}

RoundReferee::RoundReferee(const RoundRules& rules) : rules_(rules) {
  if (rules.duration_us <= 0) throw std::invalid_argument("a round's duration must be positive");
  if (rules.start_hold_us < 0 || rules.arm_empty_us < 0 || rules.end_empty_us < 0 || rules.max_gap_us < 0)
    throw std::invalid_argument("round holds must not be negative");
  if (rules.history_limit < 1) throw std::invalid_argument("the round history must keep at least one round");
}

void RoundReferee::begin(int64_t now) {
  running_ = RoundRecord{};
  running_->start_utime = now;
  state_ = RoundState::kRunning;
  reset_ = false;
  armed_ = false;  // the next round by itself only after the board was cleared
  ++revision_;
  changed_ = true;
}

void RoundReferee::finish(int64_t end_utime, RoundEnd why) {
  if (!running_) return;
  RoundRecord r = *running_;
  r.end_utime = end_utime;
  r.end = why;
  history_.push_back(r);
  if (history_.size() > rules_.history_limit)
    history_.erase(history_.begin(), history_.begin() + static_cast<std::ptrdiff_t>(history_.size() - rules_.history_limit));
  running_.reset();
  state_ = RoundState::kEnded;
  ++revision_;
  changed_ = true;
}

void RoundReferee::advance(int64_t now) {
  if (running_ && now - running_->start_utime >= rules_.duration_us)
    finish(running_->start_utime + rules_.duration_us, RoundEnd::kTimeUp);
}

void RoundReferee::board_seen(int64_t now, int blocks) {
  advance(now);
  // A gap in the stacks (camera gone, vision restarting) says nothing about the board meanwhile.
  if (last_seen_ && now - *last_seen_ > rules_.max_gap_us) {
    empty_since_.reset();
    blocks_since_.reset();
  }
  last_seen_ = now;
  if (blocks <= 0) {
    blocks_since_.reset();
    if (!empty_since_) empty_since_ = now;
    if (now - *empty_since_ >= rules_.arm_empty_us) armed_ = true;
    if (running_ && now - *empty_since_ >= rules_.end_empty_us) finish(now, RoundEnd::kBoardCleared);
    return;
  }
  empty_since_.reset();
  if (!blocks_since_) blocks_since_ = now;
  if (running_ && blocks > running_->most_blocks) {
    running_->most_blocks = blocks;
    ++revision_;
  }
  if (!running_ && rules_.auto_start && armed_ && now - *blocks_since_ >= rules_.start_hold_us) {
    begin(now);
    running_->most_blocks = blocks;
  }
}

void RoundReferee::pile(int64_t now, int score, bool balanced, int blocks) {
  advance(now);  // a round that has just ended must not take a late score
  if (score != score_) {
    score_ = score;
    changed_ = true;
  }
  if (running_ && balanced && score > running_->max_score) {
    running_->max_score = score;
    running_->blocks = blocks;
    ++revision_;
    changed_ = true;
  }
}

void RoundReferee::start(int64_t now) {
  advance(now);
  finish(now, RoundEnd::kRestarted);
  begin(now);
}

void RoundReferee::reset(int64_t now) {
  advance(now);
  finish(now, RoundEnd::kReset);
  state_ = RoundState::kIdle;
  reset_ = true;
  armed_ = false;
  changed_ = true;
}

bool RoundReferee::update(int64_t now) {
  advance(now);
  // Whole seconds as displayed (rounded up: "0:01" until the very end).
  const int64_t seconds = (remaining_ms(now) + 999) / 1000;
  if (seconds != shown_seconds_) {
    shown_seconds_ = seconds;
    changed_ = true;
  }
  const int best = day_best(now);  // also changes at midnight
  if (best != shown_day_best_) {
    shown_day_best_ = best;
    changed_ = true;
  }
  const bool out = changed_;
  changed_ = false;
  return out;
}

void RoundReferee::restore(std::vector<RoundRecord> history, std::optional<RoundRecord> running, int64_t now) {
  history_ = std::move(history);
  running_.reset();
  state_ = RoundState::kIdle;
  reset_ = false;
  if (running) {
    running_ = running;
    running_->end_utime = 0;
    state_ = RoundState::kRunning;
    advance(now);  // closed at its scheduled end when its time is up
  }
  if (!running_ && !history_.empty()) {
    reset_ = history_.back().end == RoundEnd::kReset;
    state_ = reset_ ? RoundState::kIdle : RoundState::kEnded;
  }
  if (history_.size() > rules_.history_limit)
    history_.erase(history_.begin(), history_.begin() + static_cast<std::ptrdiff_t>(history_.size() - rules_.history_limit));
  ++revision_;
  changed_ = true;
}

int64_t RoundReferee::remaining_ms(int64_t now) const {
  switch (state_) {
    case RoundState::kIdle: return duration_ms();
    case RoundState::kEnded: return 0;
    case RoundState::kRunning: break;
  }
  return std::clamp<int64_t>((rules_.duration_us - (now - running_->start_utime)) / 1000, 0, duration_ms());
}

int RoundReferee::max_score() const {
  if (running_) return running_->max_score;
  if (reset_ || history_.empty()) return 0;
  return history_.back().max_score;
}

void RoundReferee::count_today(int64_t now) const {
  const int today = local_day(now);
  if (today_.valid && today_.revision == revision_ && today_.day == today) return;
  Today t;
  t.revision = revision_;
  t.day = today;
  t.valid = true;
  // Newest first, up to the first round of an earlier day (rounds are kept in the order they started).
  for (auto it = history_.rbegin(); it != history_.rend() && local_day(it->start_utime) == today; ++it) {
    t.best = std::max(t.best, it->max_score);
    ++t.rounds;
  }
  if (running_ && local_day(running_->start_utime) == today) {
    t.best = std::max(t.best, running_->max_score);
    ++t.rounds;
  }
  today_ = t;
}

int RoundReferee::day_best(int64_t now) const {
  count_today(now);
  return today_.best;
}

int RoundReferee::rounds_today(int64_t now) const {
  count_today(now);
  return today_.rounds;
}

}  // namespace bricklayer::projection
