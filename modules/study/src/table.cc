#include "bricklayer/study/table.h"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace bricklayer::study {
namespace {

Condition condition_of(int8_t value) {
  switch (value) {
    case bricklayer::study_session_t::CONDITION_BLUE: return Condition::kBlue;
    case bricklayer::study_session_t::CONDITION_RED: return Condition::kRed;
    case bricklayer::study_session_t::CONDITION_PROPOSED: return Condition::kProposed;
    default: return Condition::kUnknown;
  }
}

std::string fixed(double value, int digits) {
  if (!std::isfinite(value)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, value);
  return buf;
}

std::string pvalue(double p) {
  if (!std::isfinite(p)) return "-";
  char buf[64];
  if (p < 1e-4) {
    std::snprintf(buf, sizeof buf, "%.2e", p);
  } else {
    std::snprintf(buf, sizeof buf, "%.4f", p);
  }
  return buf;
}

// CSV cells: numbers with full precision (a reader recomputes from them), empty when undefined.
std::string cell(double value) {
  if (!std::isfinite(value)) return "";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.10g", value);
  return buf;
}

double mean_of(const std::vector<double>& v) {
  if (v.empty()) return std::nan("");
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

}  // namespace

std::string to_string(Condition condition) {
  switch (condition) {
    case Condition::kBlue: return "blue";
    case Condition::kRed: return "red";
    case Condition::kProposed: return "proposed";
    case Condition::kUnknown: break;
  }
  return "unknown";
}

Condition parse_condition(const std::string& name) {
  if (name == "blue") return Condition::kBlue;
  if (name == "red") return Condition::kRed;
  if (name == "proposed") return Condition::kProposed;
  throw std::invalid_argument("unknown condition '" + name + "' (expected blue, red or proposed)");
}

SessionRecord& StudyCollector::session(const std::string& id, const std::string& subject, int8_t condition,
                                       int64_t utime) {
  auto [it, inserted] = sessions_.try_emplace(id);
  SessionRecord& s = it->second;
  if (inserted) {
    s.session_id = id;
    s.subject_id = subject;
    s.condition = condition_of(condition);
    attempt_utime_[id].fill(-1);
  } else {
    if (s.subject_id != subject) problems_.push_back("session " + id + ": subject '" + subject + "' after '" + s.subject_id + "'");
    if (s.condition == Condition::kUnknown) s.condition = condition_of(condition);
    else if (condition_of(condition) != s.condition && condition_of(condition) != Condition::kUnknown)
      problems_.push_back("session " + id + ": condition " + to_string(condition_of(condition)) + " after " +
                          to_string(s.condition));
  }
  s.last_utime = std::max(s.last_utime, utime);
  return s;
}

void StudyCollector::add(const bricklayer::study_session_t& msg) {
  SessionRecord& s = session(msg.session_id, msg.subject_id, msg.condition, msg.utime);
  // The newest state decides: a session aborted and never resumed stays aborted.
  if (msg.utime >= s.state_utime) {
    s.state_utime = msg.utime;
    s.aborted = msg.state == bricklayer::study_session_t::STATE_ABORTED;
    if (msg.step == bricklayer::study_session_t::STEP_DONE) s.done = true;
  }
}

void StudyCollector::add(const bricklayer::study_trial_t& msg) {
  if (msg.trial != 1 && msg.trial != 2) {
    problems_.push_back("session " + msg.session_id + ": trial " + std::to_string(msg.trial) + " (expected 1 or 2)");
    return;
  }
  SessionRecord& s = session(msg.session_id, msg.subject_id, msg.condition, msg.utime);
  const size_t k = static_cast<size_t>(msg.trial - 1);
  int64_t& kept = attempt_utime_[msg.session_id][k];
  if (msg.attempt > s.trial_attempt[k] || (msg.attempt == s.trial_attempt[k] && msg.utime >= kept)) {
    s.trial_attempt[k] = msg.attempt;
    s.trial_score[k] = msg.score;
    kept = msg.utime;
  }
}

void StudyCollector::add(const bricklayer::study_answer_t& msg) {
  if (msg.problem < 1 || msg.problem > 3) {
    problems_.push_back("session " + msg.session_id + ": problem " + std::to_string(msg.problem) + " (expected 1..3)");
    return;
  }
  if (msg.outcome < bricklayer::study_answer_t::OUTCOME_CORRECT || msg.outcome > bricklayer::study_answer_t::OUTCOME_FAILED) {
    problems_.push_back("session " + msg.session_id + ": outcome " + std::to_string(msg.outcome) + " (expected 1..3)");
    return;
  }
  SessionRecord& s = session(msg.session_id, msg.subject_id, msg.condition, msg.utime);
  const size_t k = static_cast<size_t>(msg.problem - 1);
  int64_t& kept = attempt_utime_[msg.session_id][2 + k];
  if (msg.attempt > s.answer_attempt[k] || (msg.attempt == s.answer_attempt[k] && msg.utime >= kept)) {
    s.answer_attempt[k] = msg.attempt;
    s.outcome[k] = static_cast<Outcome>(msg.outcome);
    kept = msg.utime;
  }
}

std::vector<SessionRecord> StudyCollector::sessions() const {
  std::vector<SessionRecord> out;
  for (const auto& [id, s] : sessions_) out.push_back(s);
  return out;
}

StudyTable make_table(const std::vector<SessionRecord>& sessions) {
  StudyTable table;
  std::map<Condition, std::vector<const SessionRecord*>> groups;
  for (const SessionRecord& s : sessions) {
    const std::string who = "session " + s.session_id + " (subject " + s.subject_id + "): ";
    std::string why;
    if (s.condition == Condition::kUnknown) why = "no condition";
    else if (s.aborted) why = "aborted";
    else if (!s.trial_score[0]) why = "no trial 1";
    else if (!s.trial_score[1]) why = "no trial 2";
    else {
      for (size_t k = 0; k < 3 && why.empty(); ++k) {
        if (!s.outcome[k]) why = "problem " + std::to_string(k + 1) + " not answered";
      }
    }
    if (!why.empty()) {
      table.excluded.push_back(who + why);
      continue;
    }
    groups[s.condition].push_back(&s);
  }
  for (Condition c : {Condition::kBlue, Condition::kRed, Condition::kProposed}) {
    const auto it = groups.find(c);
    if (it == groups.end()) continue;
    ConditionRow row;
    row.condition = c;
    row.subjects = it->second.size();
    std::vector<double> t1, t2;
    for (const SessionRecord* s : it->second) {
      t1.push_back(*s->trial_score[0]);
      t2.push_back(*s->trial_score[1]);
      for (size_t k = 0; k < 3; ++k) {
        if (*s->outcome[k] != Outcome::kFailed) ++row.solved[k];
        if (*s->outcome[k] == Outcome::kExcess) ++row.excess[k];
      }
      if (*s->trial_score[0] > 0) {
        row.ratios.push_back(static_cast<double>(*s->trial_score[1]) / static_cast<double>(*s->trial_score[0]));
      } else {
        table.excluded.push_back("session " + s->session_id + " (subject " + s->subject_id +
                                 "): trial 1 scored 0, no ratio (counted otherwise)");
      }
    }
    row.trial1_mean = mean_of(t1);
    row.trial2_mean = mean_of(t2);
    row.ratio = summarise(row.ratios);
    table.rows.push_back(row);
  }
  for (size_t i = 0; i < table.rows.size(); ++i) {
    for (size_t j = i + 1; j < table.rows.size(); ++j) {
      PairRow pair;
      pair.a = table.rows[i].condition;
      pair.b = table.rows[j].condition;
      pair.f = f_test(table.rows[i].ratio, table.rows[j].ratio);
      const bool equal = !pair.f.valid || pair.f.p >= kEqualVarianceAlpha;
      pair.t = t_test(table.rows[i].ratio, table.rows[j].ratio, equal);
      pair.welch = t_test(table.rows[i].ratio, table.rows[j].ratio, false);
      table.pairs.push_back(pair);
    }
  }
  return table;
}

std::string format_table(const StudyTable& table) {
  std::ostringstream out;
  char line[512];
  out << "Table 1: per condition (solved = correct or excess; excess = more added blocks than needed)\n";
  std::snprintf(line, sizeof line, "%-9s %8s %8s %12s %12s %9s %8s %11s %11s\n", "condition", "subjects", "trial 1",
                "P1 solved(x)", "P2 solved(x)", "P3 solved", "trial 2", "ratio mean", "ratio var");
  out << line;
  for (const ConditionRow& r : table.rows) {
    const std::string p1 = std::to_string(r.solved[0]) + " (" + std::to_string(r.excess[0]) + ")";
    const std::string p2 = std::to_string(r.solved[1]) + " (" + std::to_string(r.excess[1]) + ")";
    std::snprintf(line, sizeof line, "%-9s %8zu %8s %12s %12s %9zu %8s %11s %11s\n", to_string(r.condition).c_str(),
                  r.subjects, fixed(r.trial1_mean, 1).c_str(), p1.c_str(), p2.c_str(), r.solved[2],
                  fixed(r.trial2_mean, 1).c_str(), fixed(r.ratio.mean, 3).c_str(), fixed(r.ratio.variance, 4).c_str());
    out << line;
  }
  if (!table.pairs.empty()) {
    out << "\nBetween conditions, on the ratio trial 2 / trial 1 (two-sided p; t pooled unless the F-test rejects "
           "equal variances at 0.05, then Welch):\n";
    std::snprintf(line, sizeof line, "%-18s %8s %9s %8s %8s %8s %8s %8s %9s\n", "pair", "F", "df", "p(F)", "t-test",
                  "t", "df", "p(t)", "p(Welch)");
    out << line;
    for (const PairRow& p : table.pairs) {
      const std::string name = to_string(p.a) + " vs " + to_string(p.b);
      const std::string df = p.f.valid ? fixed(p.f.df1, 0) + "," + fixed(p.f.df2, 0) : "-";
      std::snprintf(line, sizeof line, "%-18s %8s %9s %8s %8s %8s %8s %8s %9s\n", name.c_str(), fixed(p.f.f, 3).c_str(),
                    df.c_str(), pvalue(p.f.p).c_str(), p.t.equal_variance ? "pooled" : "Welch", fixed(p.t.t, 3).c_str(),
                    fixed(p.t.df, 2).c_str(), pvalue(p.t.p).c_str(), pvalue(p.welch.p).c_str());
      out << line;
      if (!p.f.valid && !p.f.note.empty()) out << "  F-test not computed: " << p.f.note << "\n";
      if (!p.t.valid && !p.t.note.empty()) out << "  t-test not computed: " << p.t.note << "\n";
    }
  }
  if (!table.excluded.empty()) {
    out << "\nLeft out:\n";
    for (const std::string& e : table.excluded) out << "  " << e << "\n";
  }
  return out.str();
}

std::string table_csv(const StudyTable& table) {
  std::ostringstream out;
  out << "condition,subjects,trial1_mean,p1_solved,p1_excess,p2_solved,p2_excess,p3_solved,p3_excess,trial2_mean,"
         "ratio_n,ratio_mean,ratio_variance\n";
  for (const ConditionRow& r : table.rows) {
    out << to_string(r.condition) << ',' << r.subjects << ',' << cell(r.trial1_mean) << ',' << r.solved[0] << ','
        << r.excess[0] << ',' << r.solved[1] << ',' << r.excess[1] << ',' << r.solved[2] << ',' << r.excess[2] << ','
        << cell(r.trial2_mean) << ',' << r.ratio.n << ',' << cell(r.ratio.mean) << ',' << cell(r.ratio.variance) << '\n';
  }
  return out.str();
}

std::string tests_csv(const StudyTable& table) {
  std::ostringstream out;
  out << "a,b,n_a,n_b,f,f_df1,f_df2,f_p,t_kind,t,t_df,t_p,welch_t,welch_df,welch_p\n";
  for (const PairRow& p : table.pairs) {
    size_t na = 0, nb = 0;
    for (const ConditionRow& r : table.rows) {
      if (r.condition == p.a) na = r.ratio.n;
      if (r.condition == p.b) nb = r.ratio.n;
    }
    out << to_string(p.a) << ',' << to_string(p.b) << ',' << na << ',' << nb << ',' << cell(p.f.f) << ','
        << cell(p.f.df1) << ',' << cell(p.f.df2) << ',' << cell(p.f.p) << ',' << (p.t.equal_variance ? "pooled" : "welch")
        << ',' << cell(p.t.t) << ',' << cell(p.t.df) << ',' << cell(p.t.p) << ',' << cell(p.welch.t) << ','
        << cell(p.welch.df) << ',' << cell(p.welch.p) << '\n';
  }
  return out.str();
}

}  // namespace bricklayer::study
