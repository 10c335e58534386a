// The two-sample tests against published worked examples with known answers.
#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "bricklayer/study/statistics.h"

using namespace bricklayer::study;

// NIST/SEMATECH e-Handbook of Statistical Methods, section 1.3.5.3 "Two-Sample t-Test for Equal Means"
// (AUTO83B.DAT: miles per gallon of 249 US cars and 79 Japanese cars). Published: sample 1 N = 249,
// mean 20.14458, sd 6.41470; sample 2 N = 79, mean 30.48101, sd 6.10771; equal variances: T = -12.62059,
// pooled sd 6.34260, 326 degrees of freedom, critical value t(0.975, 326) = 1.9673; unequal variances:
// T = -12.94627, 136.8750 degrees of freedom, critical value 1.9774.
TEST_CASE("two-sample t-test: NIST e-Handbook 1.3.5.3 (AUTO83B)", "[statistics]") {
  const Summary us = summary_of(249, 20.14458, 6.41470);
  const Summary japan = summary_of(79, 30.48101, 6.10771);
  const TTest pooled = t_test(us, japan, true);
  REQUIRE(pooled.valid);
  CHECK(pooled.t == Approx(-12.62059).margin(5e-5));
  CHECK(pooled.pooled_sd == Approx(6.34260).margin(5e-5));
  CHECK(pooled.df == 326.0);
  CHECK(t_quantile(pooled.df, 0.975) == Approx(1.9673).margin(5e-5));
  // So far out in the tail that the mean difference is certain: p is tiny, and the critical value's
  // two-sided probability is exactly alpha.
  CHECK(pooled.p < 1e-20);
  CHECK(t_test(summary_of(249, 1.9673 * 6.34260 * std::sqrt(1.0 / 249 + 1.0 / 79), 6.34260), summary_of(79, 0, 6.34260), true).p ==
        Approx(0.05).margin(1e-4));

  const TTest welch = t_test(us, japan, false);
  REQUIRE(welch.valid);
  CHECK_FALSE(welch.equal_variance);
  CHECK(welch.t == Approx(-12.94627).margin(5e-5));
  CHECK(welch.df == Approx(136.8750).margin(5e-4));
  CHECK(t_quantile(welch.df, 0.975) == Approx(1.9774).margin(5e-5));
}

// NIST/SEMATECH e-Handbook, section 1.3.5.9 "F-Test for Equality of Two Variances" (JAHANMI2.DAT,
// ceramic strength, batch 1 vs batch 2). Published: N1 = 240, s1 = 65.54909; N2 = 240, s2 = 61.85425;
// F = 1.123037 with 239 and 239 degrees of freedom; critical values at alpha = 0.05:
// F(0.975; 239, 239) = 1.2894 and F(0.025; 239, 239) = 0.7756; equal variances not rejected.
TEST_CASE("F-test: NIST e-Handbook 1.3.5.9 (JAHANMI2)", "[statistics]") {
  const FTest f = f_test(summary_of(240, 0.0, 65.54909), summary_of(240, 0.0, 61.85425));
  REQUIRE(f.valid);
  CHECK(f.f == Approx(1.123037).margin(5e-6));
  CHECK(f.df1 == 239.0);
  CHECK(f.df2 == 239.0);
  CHECK(f_quantile(239, 239, 0.975) == Approx(1.2894).margin(5e-5));
  CHECK(f_quantile(239, 239, 0.025) == Approx(0.7756).margin(5e-5));
  CHECK(f.p > 0.05);  // not rejected, as published
  // At the published critical value the two-sided p is alpha.
  CHECK(f_test(summary_of(240, 0, std::sqrt(1.2894)), summary_of(240, 0, 1.0)).p == Approx(0.05).margin(2e-4));
}

// Student's sleep data (Cushny and Peebles 1905, as in "Student" 1908, Biometrika 6:1-25): extra hours of
// sleep of 10 patients under two drugs. R's documented example t.test(extra ~ group, data = sleep) prints
// t = -1.8608, df = 17.776, p-value = 0.07939 (Welch); with var.equal = TRUE t = -1.8608, df = 18,
// p-value = 0.07919; var.test(extra ~ group, data = sleep) prints F = 0.7983, num df = 9, denom df = 9,
// p-value = 0.7427.
TEST_CASE("t-test and F-test from raw values: Student's sleep data", "[statistics]") {
  const std::vector<double> drug1{0.7, -1.6, -0.2, -1.2, -0.1, 3.4, 3.7, 0.8, 0.0, 2.0};
  const std::vector<double> drug2{1.9, 0.8, 1.1, 0.1, -0.1, 4.4, 5.5, 1.6, 4.6, 3.4};
  const Summary a = summarise(drug1);
  const Summary b = summarise(drug2);
  CHECK(a.mean == Approx(0.75));
  CHECK(b.mean == Approx(2.33));
  const TTest welch = t_test(a, b, false);
  CHECK(welch.t == Approx(-1.8608).margin(5e-5));
  CHECK(welch.df == Approx(17.776).margin(5e-4));
  CHECK(welch.p == Approx(0.07939).margin(5e-6));
  const TTest pooled = t_test(a, b, true);
  CHECK(pooled.t == Approx(-1.8608).margin(5e-5));
  CHECK(pooled.df == 18.0);
  CHECK(pooled.p == Approx(0.07919).margin(5e-6));
  const FTest f = f_test(a, b);
  CHECK(f.f == Approx(0.7983).margin(5e-5));
  CHECK(f.p == Approx(0.7427).margin(5e-5));
  // Swapping the groups: the same two-sided p, reciprocal F, opposite t.
  CHECK(f_test(b, a).p == Approx(f.p).margin(1e-12));
  CHECK(t_test(b, a, false).t == Approx(-welch.t));
}

TEST_CASE("degenerate samples are not tested, and say why", "[statistics]") {
  CHECK(std::isnan(summarise({}).mean));
  CHECK(std::isnan(summarise({3.0}).variance));
  const FTest one = f_test(summarise({1.0}), summarise({1.0, 2.0}));
  CHECK_FALSE(one.valid);
  CHECK(one.note == "each group needs at least 2 values");
  const FTest zero = f_test(summarise({1.0, 1.0}), summarise({1.0, 2.0}));
  CHECK_FALSE(zero.valid);
  CHECK(zero.note == "a variance is zero");
  const TTest flat = t_test(summarise({1.0, 1.0}), summarise({2.0, 2.0}), true);
  CHECK_FALSE(flat.valid);
  // One flat group is still a valid t-test.
  CHECK(t_test(summarise({1.0, 1.0, 1.0}), summarise({2.0, 3.0, 4.0}), true).valid);
}
