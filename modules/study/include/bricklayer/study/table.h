// The seed paper's Table 1 from the study messages of any number of sessions: per condition, the first
// trial's average score, how many subjects solved each problem and how many of them used excess blocks,
// the second trial's average score, and the mean and variance of the ratio trial 2 / trial 1; between
// every two conditions, the F-test for equal variances of that ratio and the t-test of its means (pooled
// when the F-test does not reject equal variances at alpha = 0.05, else Welch's; both are given).
//
// Which sessions count: a known condition, not aborted, both trials and all three problems answered.
// For a step that was repeated, its last attempt counts. A subject whose first trial scored 0 has no
// ratio (counted in the row, left out of the ratio's mean and variance). Everything left out is listed.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "bricklayer/study/checker.h"
#include "bricklayer/study/statistics.h"
#include "bricklayer/study_answer_t.hpp"
#include "bricklayer/study_session_t.hpp"
#include "bricklayer/study_trial_t.hpp"

namespace bricklayer::study {

enum class Condition { kUnknown = 0, kBlue = 1, kRed = 2, kProposed = 3 };  // study_session_t::CONDITION_*
std::string to_string(Condition condition);
// "blue", "red" or "proposed"; throws std::invalid_argument otherwise.
Condition parse_condition(const std::string& name);

struct SessionRecord {
  std::string session_id;
  std::string subject_id;
  Condition condition = Condition::kUnknown;
  bool aborted = false;
  bool done = false;  // the driver reached STEP_DONE
  std::array<std::optional<int32_t>, 2> trial_score;  // last attempt of trial 1 and 2
  std::array<int32_t, 2> trial_attempt{0, 0};
  std::array<std::optional<Outcome>, 3> outcome;  // last attempt of problem 1..3
  std::array<int32_t, 3> answer_attempt{0, 0, 0};
  int64_t last_utime = 0;
  int64_t state_utime = -1;  // utime of the newest study_session_t applied
};

// Gathers study messages (in any order; later attempts replace earlier ones, by attempt then utime).
class StudyCollector {
 public:
  void add(const bricklayer::study_session_t& msg);
  void add(const bricklayer::study_trial_t& msg);
  void add(const bricklayer::study_answer_t& msg);
  // Messages that contradicted their session (another condition or subject) or carried impossible values.
  const std::vector<std::string>& problems() const { return problems_; }
  std::vector<SessionRecord> sessions() const;  // sorted by session id

 private:
  SessionRecord& session(const std::string& id, const std::string& subject, int8_t condition, int64_t utime);
  std::map<std::string, SessionRecord> sessions_;
  std::map<std::string, std::array<int64_t, 5>> attempt_utime_;  // per session: utime of the attempt kept per step
  std::vector<std::string> problems_;
};

struct ConditionRow {
  Condition condition = Condition::kUnknown;
  size_t subjects = 0;
  double trial1_mean = 0.0;
  std::array<size_t, 3> solved{0, 0, 0};  // correct or excess
  std::array<size_t, 3> excess{0, 0, 0};
  double trial2_mean = 0.0;
  Summary ratio;  // of trial 2 / trial 1 over subjects with a nonzero trial 1
  std::vector<double> ratios;
};

struct PairRow {
  Condition a = Condition::kUnknown;
  Condition b = Condition::kUnknown;
  FTest f;
  TTest t;      // the one chosen by the F-test
  TTest welch;  // always Welch's, for reference
};

struct StudyTable {
  std::vector<ConditionRow> rows;   // blue, red, proposed (only conditions with subjects)
  std::vector<PairRow> pairs;       // every two rows
  std::vector<std::string> excluded;  // "session s3 (subject p07): aborted", ...
};

inline constexpr double kEqualVarianceAlpha = 0.05;

StudyTable make_table(const std::vector<SessionRecord>& sessions);

std::string format_table(const StudyTable& table);  // the text report
std::string table_csv(const StudyTable& table);     // one line per condition, with a header
std::string tests_csv(const StudyTable& table);     // one line per pair of conditions, with a header

}  // namespace bricklayer::study
