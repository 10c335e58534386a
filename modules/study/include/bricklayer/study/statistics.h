// Two-sample statistics for the study's analysis: summaries, the F-test for equal variances and Student's
// two-sample t-test (pooled, equal variances) or Welch's (unequal). The distributions come from
// Boost.Math (students_t, fisher_f); nothing here evaluates a special function itself.
// All p-values are two-sided.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace bricklayer::study {

struct Summary {
  size_t n = 0;
  double mean = 0.0;      // NaN when n == 0
  double variance = 0.0;  // sample variance (n - 1 in the denominator); NaN when n < 2
  double sd() const;      // sqrt(variance)
};

Summary summarise(const std::vector<double>& values);
// From published summary figures (n, mean, standard deviation), e.g. a handbook's worked example.
Summary summary_of(size_t n, double mean, double sd);

struct FTest {
  double f = 0.0;        // variance of a / variance of b
  double df1 = 0.0;      // n_a - 1
  double df2 = 0.0;      // n_b - 1
  double p = 0.0;        // two-sided: 2 min(P(F <= f), P(F >= f))
  bool valid = false;    // false when a sample has n < 2 or a variance is zero or not finite (then NaN fields)
  std::string note;      // why not valid
};

struct TTest {
  bool equal_variance = true;  // pooled (Student) or Welch
  double t = 0.0;              // (mean a - mean b) / standard error
  double df = 0.0;             // n_a + n_b - 2 (pooled) or Welch-Satterthwaite
  double p = 0.0;              // two-sided
  double pooled_sd = 0.0;      // pooled only
  bool valid = false;
  std::string note;
};

FTest f_test(const Summary& a, const Summary& b);
TTest t_test(const Summary& a, const Summary& b, bool equal_variance);

// Quantiles, for checking against published critical values.
double t_quantile(double df, double probability);
double f_quantile(double df1, double df2, double probability);

}  // namespace bricklayer::study
