// Table 1 from recorded logs: the simulated study of study_messages.h through real LCM log files.
#include <cmath>
#include <cstdio>
#include <string>
#include <unistd.h>

#include <catch2/catch.hpp>

#include "bricklayer/study/study_log.h"
#include "bricklayer/study/table.h"
#include "study_messages.h"

using namespace bricklayer::study;
using namespace study_test;

namespace {

std::string temp_log(const std::string& name) {
  return std::string(BRICKLAYER_BINARY_DIR) + "/tests/study/" + name + "_" + std::to_string(getpid()) + ".lcmlog";
}

const ConditionRow& row(const StudyTable& t, Condition c) {
  for (const ConditionRow& r : t.rows) {
    if (r.condition == c) return r;
  }
  FAIL("no row for " << to_string(c));
  throw;
}

}  // namespace

TEST_CASE("report: Table 1 of a scripted study read back from two logs", "[report]") {
  const std::vector<Subject> subjects = scripted_subjects();
  const std::string first = temp_log("study_a");
  const std::string second = temp_log("study_b");
  {
    LogWriter a(first);
    for (size_t i = 0; i < 5; ++i) a.session(subjects[i]);
    // A session aborted after trial 1: left out.
    const Subject quit{"s11", "p11", kBlue, 500, 0, {C, C, C}};
    a.state(quit, bricklayer::study_session_t::STEP_TRIAL_1, bricklayer::study_session_t::STATE_RUNNING);
    a.trial(quit, 1, 500);
    a.state(quit, bricklayer::study_session_t::STEP_PROBLEM_1, bricklayer::study_session_t::STATE_ABORTED);
    // Unrelated traffic and a corrupt study message: skipped and counted.
    a.raw("BL_STACK", {1, 2, 3});
    a.raw(kTrialChannel, {0xde, 0xad});
  }
  {
    LogWriter b(second);
    for (size_t i = 5; i < subjects.size(); ++i) b.session(subjects[i]);
    // s08 repeated problem 3 and solved it on the second attempt: the last attempt counts.
    b.answer(subjects[7], 3, C, 2);
    // s06 repeated trial 1 with a worse score: the repeat counts (110 -> 55 would change the ratio to 2.2).
    b.trial(subjects[5], 1, 55, 2);
    // A session with no condition: left out.
    Subject unknown = subjects[0];
    unknown.session = "s12";
    unknown.subject = "p12";
    unknown.condition = bricklayer::study_session_t::CONDITION_UNKNOWN;
    b.session(unknown);
  }
  StudyCollector collector;
  const LogReadCounts a = read_study_log(first, collector);
  const LogReadCounts b = read_study_log(second, collector);
  CHECK(a.bad_messages == 1);
  CHECK(a.errors.size() == 1);
  CHECK(a.events == 5 * 12 + 3 + 2);  // a session is 7 states, 2 trials and 3 answers
  CHECK(b.bad_messages == 0);
  CHECK(a.study_messages == 5 * 12 + 3);
  CHECK(b.study_messages == 5 * 12 + 2 + 12);
  std::remove(first.c_str());
  std::remove(second.c_str());

  const StudyTable t = make_table(collector.sessions());
  REQUIRE(t.rows.size() == 3);
  const ConditionRow& blue = row(t, Condition::kBlue);
  CHECK(blue.subjects == 3);
  CHECK(blue.trial1_mean == Approx(100.0));
  CHECK(blue.solved == std::array<size_t, 3>{2, 3, 1});
  CHECK(blue.excess == std::array<size_t, 3>{1, 1, 0});
  CHECK(blue.trial2_mean == Approx(340.0 / 3));
  CHECK(blue.ratio.mean == Approx((1.1 + 1.25 + 1.0) / 3));
  CHECK(blue.ratio.variance == Approx(0.0158333333));

  const ConditionRow& red = row(t, Condition::kRed);
  CHECK(red.subjects == 3);
  CHECK(red.trial1_mean == Approx((90 + 100 + 55) / 3.0));
  CHECK(red.solved == std::array<size_t, 3>{2, 3, 2});
  CHECK(red.excess == std::array<size_t, 3>{1, 1, 0});
  CHECK(red.ratio.mean == Approx((1.0 + 1.3 + 2.2) / 3));

  const ConditionRow& proposed = row(t, Condition::kProposed);
  CHECK(proposed.subjects == 4);
  CHECK(proposed.trial1_mean == Approx(87.5));
  CHECK(proposed.trial2_mean == Approx(137.5));
  CHECK(proposed.solved == std::array<size_t, 3>{3, 3, 3});
  CHECK(proposed.excess == std::array<size_t, 3>{1, 0, 0});
  CHECK(proposed.ratio.n == 3);  // s10 scored 0 in trial 1: no ratio
  CHECK(proposed.ratio.mean == Approx(1.6));
  CHECK(proposed.ratio.variance == Approx(0.13));

  REQUIRE(t.pairs.size() == 3);
  CHECK(t.pairs[0].a == Condition::kBlue);
  CHECK(t.pairs[0].b == Condition::kRed);
  CHECK(t.pairs[2].a == Condition::kRed);
  CHECK(t.pairs[2].b == Condition::kProposed);
  for (const PairRow& p : t.pairs) {
    const Summary& sa = row(t, p.a).ratio;
    const Summary& sb = row(t, p.b).ratio;
    const FTest f = f_test(sa, sb);
    CHECK(p.f.f == Approx(f.f));
    CHECK(p.f.p == Approx(f.p));
    CHECK(p.t.equal_variance == (f.p >= kEqualVarianceAlpha));
    CHECK(p.t.p == Approx(t_test(sa, sb, p.t.equal_variance).p));
    CHECK(p.welch.p == Approx(t_test(sa, sb, false).p));
  }
  // blue vs proposed by hand: pooled variance (2 x 0.0158333 + 2 x 0.13) / 4 = 0.0729167,
  // t = (1.116667 - 1.6) / sqrt(0.0729167 x 2/3) = -2.19220, 4 degrees of freedom.
  CHECK(t.pairs[1].t.equal_variance);
  CHECK(t.pairs[1].t.t == Approx(-2.19220).margin(1e-4));
  CHECK(t.pairs[1].t.df == 4.0);
  CHECK(t.pairs[1].f.f == Approx(0.0158333333 / 0.13));

  const std::string text = format_table(t);
  CHECK(text.find("session s11 (subject p11): aborted") != std::string::npos);
  CHECK(text.find("session s12 (subject p12): no condition") != std::string::npos);
  CHECK(text.find("session s10 (subject p10): trial 1 scored 0, no ratio") != std::string::npos);
  CHECK(text.find("blue vs proposed") != std::string::npos);

  const std::string csv = table_csv(t);
  CHECK(csv.rfind("condition,subjects,trial1_mean,p1_solved,p1_excess,p2_solved,p2_excess,p3_solved,p3_excess,"
                  "trial2_mean,ratio_n,ratio_mean,ratio_variance\n",
                  0) == 0);
  CHECK(csv.find("\nproposed,4,87.5,3,1,3,0,3,0,137.5,3,1.6,0.13\n") != std::string::npos);
  const std::string tests = tests_csv(t);
  CHECK(tests.find("\nblue,proposed,3,3,") != std::string::npos);
}

TEST_CASE("report: a file that is not an LCM log is a clear error", "[report]") {
  const std::string path = temp_log("not_a_log");
  {
    std::FILE* f = std::fopen(path.c_str(), "w");
    std::fputs("hello", f);
    std::fclose(f);
  }
  StudyCollector collector;
  // LCM reads an unrecognised file as an empty log or fails to open it; either way nothing is counted.
  try {
    const LogReadCounts c = read_study_log(path, collector);
    CHECK(c.study_messages == 0);
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("cannot be opened as an LCM log") != std::string::npos);
  }
  std::remove(path.c_str());
  CHECK_THROWS_WITH(read_study_log(path + ".missing", collector), Catch::Contains("cannot be opened as an LCM log"));
  CHECK(collector.sessions().empty());
}
