// A simulated study written as real LCM logs, the way the session driver publishes it: each subject's
// session states, two trials and three answers. Shared by the report test and the CLI test.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "bricklayer/study/channels.h"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "bricklayer/study_trial_t.hpp"

namespace study_test {

struct Subject {
  std::string session;
  std::string subject;
  int8_t condition;
  int32_t trial1;
  int32_t trial2;
  int8_t outcomes[3];  // study_answer_t::OUTCOME_*
};

class LogWriter {
 public:
  explicit LogWriter(const std::string& path) : log_(new lcm::LogFile(path, "w")) {}
  ~LogWriter() { delete log_; }
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  template <typename T>
  void write(const char* channel, const T& msg) {
    std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    raw(channel, buf);
  }
  void raw(const char* channel, std::vector<uint8_t> bytes) {
    lcm::LogEvent e{};
    e.eventnum = count_++;
    e.timestamp = utime_;
    e.channel = channel;
    e.datalen = static_cast<int32_t>(bytes.size());
    e.data = bytes.data();
    log_->writeEvent(&e);
  }
  int64_t tick() { return utime_ += 1000; }

  void state(const Subject& s, int8_t step, int8_t state) {
    bricklayer::study_session_t m{};
    m.utime = tick();
    m.session_id = s.session;
    m.subject_id = s.subject;
    m.condition = s.condition;
    m.step = step;
    m.state = state;
    m.attempt = 1;
    write(bricklayer::study::kSessionChannel, m);
  }
  void trial(const Subject& s, int8_t which, int32_t score, int32_t attempt = 1) {
    bricklayer::study_trial_t m{};
    m.utime = tick();
    m.session_id = s.session;
    m.subject_id = s.subject;
    m.condition = s.condition;
    m.trial = which;
    m.attempt = attempt;
    m.duration_ms = 120'000;
    m.score = score;
    m.num_blocks = 5;
    write(bricklayer::study::kTrialChannel, m);
  }
  void answer(const Subject& s, int8_t problem, int8_t outcome, int32_t attempt = 1) {
    bricklayer::study_answer_t m{};
    m.utime = tick();
    m.session_id = s.session;
    m.subject_id = s.subject;
    m.condition = s.condition;
    m.problem = problem;
    m.name = "p" + std::to_string(problem);
    m.attempt = attempt;
    m.outcome = outcome;
    m.stands = outcome != bricklayer::study_answer_t::OUTCOME_FAILED;
    m.minimum_added = problem == 3 ? -1 : 3 - problem;
    m.blocks_added = m.minimum_added + (outcome == bricklayer::study_answer_t::OUTCOME_EXCESS ? 1 : 0);
    m.reason = "scripted";
    write(bricklayer::study::kAnswerChannel, m);
  }
  // A whole session as the protocol runs it.
  void session(const Subject& s) {
    using S = bricklayer::study_session_t;
    state(s, S::STEP_WAITING, S::STATE_READY);
    state(s, S::STEP_TRIAL_1, S::STATE_RUNNING);
    trial(s, 1, s.trial1);
    for (int8_t p = 0; p < 3; ++p) {
      state(s, static_cast<int8_t>(S::STEP_PROBLEM_1 + p), S::STATE_RUNNING);
      answer(s, static_cast<int8_t>(p + 1), s.outcomes[p]);
    }
    state(s, S::STEP_TRIAL_2, S::STATE_RUNNING);
    trial(s, 2, s.trial2);
    state(s, S::STEP_DONE, S::STATE_FINISHED);
  }

 private:
  lcm::LogFile* log_;  // held by pointer: lcm::LogFile cannot be copied
  int64_t utime_ = 1'700'000'000'000'000;
  int64_t count_ = 0;
};

constexpr int8_t C = bricklayer::study_answer_t::OUTCOME_CORRECT;
constexpr int8_t X = bricklayer::study_answer_t::OUTCOME_EXCESS;
constexpr int8_t F = bricklayer::study_answer_t::OUTCOME_FAILED;
constexpr int8_t kBlue = bricklayer::study_session_t::CONDITION_BLUE;
constexpr int8_t kRed = bricklayer::study_session_t::CONDITION_RED;
constexpr int8_t kProposed = bricklayer::study_session_t::CONDITION_PROPOSED;

// Ten subjects with known answers (see report_test.cc for the expected table).
inline std::vector<Subject> scripted_subjects() {
  return {
      {"s01", "p01", kBlue, 100, 110, {C, C, C}},     {"s02", "p02", kBlue, 120, 150, {X, C, F}},
      {"s03", "p03", kBlue, 80, 80, {F, X, F}},       {"s04", "p04", kRed, 90, 90, {C, C, C}},
      {"s05", "p05", kRed, 100, 130, {X, X, C}},      {"s06", "p06", kRed, 110, 121, {F, C, F}},
      {"s07", "p07", kProposed, 100, 150, {C, C, C}}, {"s08", "p08", kProposed, 50, 100, {C, C, F}},
      {"s09", "p09", kProposed, 200, 260, {X, C, C}}, {"s10", "p10", kProposed, 0, 40, {F, F, F}},
  };
}

}  // namespace study_test
