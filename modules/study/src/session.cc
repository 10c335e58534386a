#include "bricklayer/study/session.h"

#include <stdexcept>

namespace bricklayer::study {
namespace {

using S = bricklayer::study_session_t;
using A = bricklayer::study_answer_t;

bool is_trial(int8_t step) { return step == S::STEP_TRIAL_1 || step == S::STEP_TRIAL_2; }

const char* step_name(int8_t step) {
  switch (step) {
    case S::STEP_TRIAL_1: return "the first game";
    case S::STEP_PROBLEM_1: return "problem 1";
    case S::STEP_PROBLEM_2: return "problem 2";
    case S::STEP_PROBLEM_3: return "problem 3";
    case S::STEP_TRIAL_2: return "the second game";
    default: return "the session";
  }
}

}  // namespace

SessionProtocol::SessionProtocol(SessionSetup setup, std::shared_ptr<const StabiliseChecker> problem1,
                                 std::shared_ptr<const StabiliseChecker> problem2, Problem problem3)
    : setup_(std::move(setup)), stabilise_{std::move(problem1), std::move(problem2)}, score_problem_(std::move(problem3)) {
  if (setup_.session_id.empty() || setup_.subject_id.empty()) {
    throw std::invalid_argument("a study session needs a session id and a subject id");
  }
  if (setup_.condition == Condition::kUnknown) throw std::invalid_argument("a study session needs a condition");
  if (!stabilise_[0] || !stabilise_[1]) throw std::invalid_argument("problems 1 and 2 must be stabilise problems");
  if (score_problem_.kind != ProblemKind::kScore) {
    throw std::invalid_argument("problem 3 must be a score problem, " + score_problem_.name + " is not");
  }
  if (setup_.trial_ms <= 0) throw std::invalid_argument("a trial must last longer than 0 ms");
}

bool SessionProtocol::finished() const { return step_ == S::STEP_DONE || state_ == S::STATE_ABORTED; }

int SessionProtocol::problem_index() const {
  if (step_ >= S::STEP_PROBLEM_1 && step_ <= S::STEP_PROBLEM_3) return step_ - S::STEP_PROBLEM_1;
  return -1;
}

int64_t SessionProtocol::step_limit_ms() const {
  if (is_trial(step_)) return setup_.trial_ms;
  const int p = problem_index();
  if (p == 0 || p == 1) return stabilise_[static_cast<size_t>(p)]->problem().time_limit_ms;
  if (p == 2) return score_problem_.time_limit_ms;
  return 0;
}

int64_t SessionProtocol::elapsed_ms(int64_t utime) const {
  int64_t ms = elapsed_before_ms_;
  if (state_ == S::STATE_RUNNING) ms += (utime - running_since_) / 1000;
  return ms;
}

bool SessionProtocol::start(int64_t utime) {
  if (step_ != S::STEP_WAITING || state_ == S::STATE_ABORTED) return false;
  begin_step(S::STEP_TRIAL_1, utime);
  return true;
}

void SessionProtocol::begin_step(int8_t step, int64_t utime) {
  step_ = step;
  state_ = S::STATE_READY;
  ++attempts_[static_cast<size_t>(step)];
  elapsed_before_ms_ = 0;
  running_since_ = utime;
  clear_since_.reset();
  best_score_ = best_blocks_ = collapses_ = 0;
  last_balanced_.reset();
  last_pile_.reset();
  settled_verdict_.reset();
  judge_.reset();
  out_.state_changed = true;
}

void SessionProtocol::run_step(int64_t utime) {
  state_ = S::STATE_RUNNING;
  running_since_ = utime;
  out_.state_changed = true;
  if (is_trial(step_)) {
    out_.rounds.push_back(RoundCommand::kStart);
  } else if (problem_index() >= 0) {
    out_.problems.push_back(problem_message(problem_index(), utime));
    if (problem_index() == 2) {
      judge_.emplace(score_problem_);
      judge_->start(utime);
    }
  }
}

void SessionProtocol::finish_step(int64_t utime) {
  if (is_trial(step_)) out_.rounds.push_back(RoundCommand::kReset);
  if (step_ == S::STEP_TRIAL_2) {
    step_ = S::STEP_DONE;
    state_ = S::STATE_FINISHED;
    out_.state_changed = true;
    return;
  }
  begin_step(static_cast<int8_t>(step_ + 1), utime);
}

bool SessionProtocol::pause(int64_t utime) {
  if (state_ != S::STATE_RUNNING) return false;
  elapsed_before_ms_ = elapsed_ms(utime);
  state_ = S::STATE_PAUSED;
  out_.state_changed = true;
  return true;
}

bool SessionProtocol::resume(int64_t utime) {
  if (state_ != S::STATE_PAUSED) return false;
  state_ = S::STATE_RUNNING;
  running_since_ = utime;
  // A hold that was under way when the pause began starts again: the subject may have touched the pile.
  settled_verdict_.reset();
  out_.state_changed = true;
  return true;
}

bool SessionProtocol::repeat(int64_t utime) {
  if (finished() || step_ == S::STEP_WAITING) return false;
  int8_t step = step_;
  // In READY the step has not begun: the experimenter means the one just finished.
  if (state_ == S::STATE_READY && step > S::STEP_TRIAL_1) --step;
  if (is_trial(step_) && state_ != S::STATE_READY) out_.rounds.push_back(RoundCommand::kReset);
  begin_step(step, utime);
  return true;
}

bool SessionProtocol::abort(int64_t utime) {
  if (finished()) return false;
  if (is_trial(step_) && (state_ == S::STATE_RUNNING || state_ == S::STATE_PAUSED)) out_.rounds.push_back(RoundCommand::kReset);
  elapsed_before_ms_ = elapsed_ms(utime);
  state_ = S::STATE_ABORTED;
  out_.state_changed = true;
  return true;
}

bool SessionProtocol::done(int64_t utime) {
  const int p = problem_index();
  if (state_ != S::STATE_RUNNING || (p != 0 && p != 1)) return false;
  answer_stabilise(utime, "done");
  return true;
}

void SessionProtocol::observe(const Observation& o) {
  if (finished() || step_ == S::STEP_WAITING || !o.valid) return;
  if (state_ == S::STATE_READY) {
    if (o.stack.blocks.empty()) {
      if (!clear_since_) clear_since_ = o.utime;
    } else {
      clear_since_.reset();
    }
    tick(o.utime);
    return;
  }
  if (state_ != S::STATE_RUNNING) return;
  if (is_trial(step_)) {
    const int32_t n = static_cast<int32_t>(o.stack.blocks.size());
    if (o.balanced && n > 0 && o.score > best_score_) {
      best_score_ = o.score;
      best_blocks_ = n;
    }
    if (n > 0) {
      if (last_balanced_ && *last_balanced_ && !o.balanced) ++collapses_;
      last_balanced_ = o.balanced;
    }
  } else if (problem_index() == 2) {
    judge_->observe(o.utime, static_cast<int32_t>(o.stack.blocks.size()), o.balanced, o.score);
  } else {
    last_pile_ = o;
    const StabiliseChecker& checker = *stabilise_[static_cast<size_t>(problem_index())];
    const Verdict v = checker.check(o.stack);
    const bool complete = v.outcome != Outcome::kFailed;
    if (!complete) {
      settled_verdict_.reset();
    } else if (!settled_verdict_ || settled_verdict_->outcome != v.outcome ||
               settled_verdict_->blocks_added != v.blocks_added) {
      settled_verdict_ = v;
      settled_since_ = o.utime;
    }
  }
  tick(o.utime);
}

void SessionProtocol::tick(int64_t utime) {
  if (finished() || step_ == S::STEP_WAITING) return;
  if (state_ == S::STATE_READY) {
    if (clear_since_ && utime - *clear_since_ >= setup_.clear_ms * 1000) run_step(utime);
    return;
  }
  if (state_ != S::STATE_RUNNING) return;
  const int64_t elapsed = elapsed_ms(utime);
  const int64_t limit = step_limit_ms();
  if (is_trial(step_)) {
    if (elapsed >= limit) {
      bricklayer::study_trial_t t{};
      t.utime = utime;
      t.session_id = setup_.session_id;
      t.subject_id = setup_.subject_id;
      t.condition = static_cast<int8_t>(setup_.condition);
      t.trial = step_ == S::STEP_TRIAL_1 ? 1 : 2;
      t.attempt = attempts_[static_cast<size_t>(step_)];
      t.duration_ms = limit;
      t.score = best_score_;
      t.num_blocks = best_blocks_;
      t.collapses = collapses_;
      out_.trials.push_back(t);
      finish_step(utime);
    }
    return;
  }
  const int p = problem_index();
  if (p == 2) {
    if (judge_->solved() || (limit > 0 && elapsed >= limit)) answer_score(utime);
    return;
  }
  if (settled_verdict_ && utime - settled_since_ >= setup_.settle_ms * 1000) {
    answer_stabilise(utime, "settled");
  } else if (limit > 0 && elapsed >= limit) {
    answer_stabilise(utime, "time up");
  }
}

void SessionProtocol::answer_stabilise(int64_t utime, const char* how) {
  const int p = problem_index();
  const StabiliseChecker& checker = *stabilise_[static_cast<size_t>(p)];
  Verdict v;
  if (last_pile_) {
    v = checker.check(last_pile_->stack, elapsed_ms(utime));
  } else {
    v.minimum_added = checker.minimum().minimum;
    v.time_ms = elapsed_ms(utime);
    v.reason = "no pile was seen";
  }
  A a{};
  a.utime = utime;
  a.session_id = setup_.session_id;
  a.subject_id = setup_.subject_id;
  a.condition = static_cast<int8_t>(setup_.condition);
  a.problem = static_cast<int8_t>(p + 1);
  a.name = checker.problem().name;
  a.attempt = attempts_[static_cast<size_t>(step_)];
  a.outcome = static_cast<int8_t>(v.outcome);
  a.stands = v.stands;
  a.blocks_added = v.blocks_added;
  a.minimum_added = v.minimum_added;
  a.score = v.score;
  a.time_ms = v.time_ms;
  a.position_tolerance = checker.problem().position_tolerance;
  a.reason = v.reason + " (" + how + ")";
  out_.answers.push_back(a);
  finish_step(utime);
}

void SessionProtocol::answer_score(int64_t utime) {
  const Verdict v = judge_->verdict(utime);
  A a{};
  a.utime = utime;
  a.session_id = setup_.session_id;
  a.subject_id = setup_.subject_id;
  a.condition = static_cast<int8_t>(setup_.condition);
  a.problem = 3;
  a.name = score_problem_.name;
  a.attempt = attempts_[static_cast<size_t>(step_)];
  a.outcome = static_cast<int8_t>(v.outcome);
  a.stands = v.stands;
  a.blocks_added = v.blocks_added;
  a.minimum_added = -1;
  a.score = v.score;
  a.time_ms = v.time_ms;
  a.position_tolerance = 0.0;
  a.reason = v.reason;
  out_.answers.push_back(a);
  finish_step(utime);
}

SessionOutputs SessionProtocol::take_outputs() {
  SessionOutputs out = std::move(out_);
  out_ = SessionOutputs{};
  return out;
}

std::string SessionProtocol::instruction() const {
  if (state_ == S::STATE_ABORTED) return "The session has ended. Thank you!";
  if (step_ == S::STEP_DONE) return "That was all. Thank you!";
  if (step_ == S::STEP_WAITING) return "Please wait: the session will start soon.";
  if (state_ == S::STATE_PAUSED) return "Paused. Please wait.";
  if (state_ == S::STATE_READY) return std::string("Take every block off the board to begin ") + step_name(step_) + ".";
  if (is_trial(step_)) {
    return "Build a pile that reaches as far as you can beyond the edge. Only a pile that stands counts.";
  }
  const int p = problem_index();
  if (p == 2) return score_problem_.instruction;
  return stabilise_[static_cast<size_t>(p)]->problem().instruction;
}

bricklayer::study_session_t SessionProtocol::state(int64_t utime) const {
  S s{};
  s.utime = utime;
  s.session_id = setup_.session_id;
  s.subject_id = setup_.subject_id;
  s.condition = static_cast<int8_t>(setup_.condition);
  s.step = step_;
  s.state = state_;
  s.attempt = step_ >= 0 && step_ < 7 ? std::max(1, attempts_[static_cast<size_t>(step_)]) : 1;
  s.step_duration_ms = step_limit_ms();
  s.step_remaining_ms = s.step_duration_ms > 0 ? std::max<int64_t>(0, s.step_duration_ms - elapsed_ms(utime)) : 0;
  s.instruction = instruction();
  return s;
}

bricklayer::study_problem_t SessionProtocol::problem_message(int index, int64_t utime) const {
  bricklayer::study_problem_t m{};
  m.utime = utime;
  m.session_id = setup_.session_id;
  m.problem = static_cast<int8_t>(index + 1);
  if (index < 2) {
    const Problem& p = stabilise_[static_cast<size_t>(index)]->problem();
    m.name = p.name;
    m.kind = bricklayer::study_problem_t::KIND_STABILISE;
    m.instruction = p.instruction;
    m.time_limit_ms = p.time_limit_ms;
    m.minimum_added = stabilise_[static_cast<size_t>(index)]->minimum().minimum;
    for (const auto& b : p.pile.blocks) {
      bricklayer::block_t bt{};
      bt.id = b.id;
      bt.row = b.row;
      bt.x = b.x;
      m.blocks.push_back(bt);
    }
    m.num_blocks = static_cast<int32_t>(m.blocks.size());
  } else {
    m.name = score_problem_.name;
    m.kind = bricklayer::study_problem_t::KIND_SCORE;
    m.instruction = score_problem_.instruction;
    m.time_limit_ms = score_problem_.time_limit_ms;
    m.minimum_added = -1;
    m.min_score = score_problem_.min_score;
    m.max_blocks = score_problem_.max_blocks;
  }
  return m;
}

std::optional<bricklayer::study_problem_t> SessionProtocol::current_problem(int64_t utime) const {
  const int p = problem_index();
  if (p < 0 || finished()) return std::nullopt;
  return problem_message(p, utime);
}

}  // namespace bricklayer::study
