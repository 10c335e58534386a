#include "bricklayer/study/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/students_t.hpp>

namespace bricklayer::study {
namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

double Summary::sd() const { return std::sqrt(variance); }

Summary summarise(const std::vector<double>& values) {
  Summary s;
  s.n = values.size();
  if (s.n == 0) {
    s.mean = kNaN;
    s.variance = kNaN;
    return s;
  }
  double sum = 0.0;
  for (double v : values) sum += v;
  s.mean = sum / static_cast<double>(s.n);
  if (s.n < 2) {
    s.variance = kNaN;
    return s;
  }
  double ss = 0.0;  // two-pass: no cancellation
  for (double v : values) ss += (v - s.mean) * (v - s.mean);
  s.variance = ss / static_cast<double>(s.n - 1);
  return s;
}

Summary summary_of(size_t n, double mean, double sd) {
  Summary s;
  s.n = n;
  s.mean = mean;
  s.variance = sd * sd;
  return s;
}

FTest f_test(const Summary& a, const Summary& b) {
  FTest r;
  r.f = r.df1 = r.df2 = r.p = kNaN;
  if (a.n < 2 || b.n < 2) {
    r.note = "each group needs at least 2 values";
    return r;
  }
  r.df1 = static_cast<double>(a.n - 1);
  r.df2 = static_cast<double>(b.n - 1);
  if (!std::isfinite(a.variance) || !std::isfinite(b.variance) || a.variance <= 0 || b.variance <= 0) {
    r.note = "a variance is zero";
    return r;
  }
  r.f = a.variance / b.variance;
  const boost::math::fisher_f dist(r.df1, r.df2);
  const double lower = boost::math::cdf(dist, r.f);
  const double upper = boost::math::cdf(boost::math::complement(dist, r.f));
  r.p = std::min(1.0, 2.0 * std::min(lower, upper));
  r.valid = true;
  return r;
}

TTest t_test(const Summary& a, const Summary& b, bool equal_variance) {
  TTest r;
  r.equal_variance = equal_variance;
  r.t = r.df = r.p = r.pooled_sd = kNaN;
  if (a.n < 2 || b.n < 2) {
    r.note = "each group needs at least 2 values";
    return r;
  }
  const double na = static_cast<double>(a.n);
  const double nb = static_cast<double>(b.n);
  double se = 0.0;
  if (equal_variance) {
    r.df = na + nb - 2.0;
    r.pooled_sd = std::sqrt(((na - 1.0) * a.variance + (nb - 1.0) * b.variance) / r.df);
    se = r.pooled_sd * std::sqrt(1.0 / na + 1.0 / nb);
  } else {
    const double va = a.variance / na;
    const double vb = b.variance / nb;
    se = std::sqrt(va + vb);
    r.df = (va + vb) * (va + vb) / (va * va / (na - 1.0) + vb * vb / (nb - 1.0));
  }
  if (!std::isfinite(se) || se <= 0 || !std::isfinite(r.df)) {
    r.note = "zero variance in both groups";
    return r;
  }
  r.t = (a.mean - b.mean) / se;
  const boost::math::students_t dist(r.df);
  r.p = std::min(1.0, 2.0 * boost::math::cdf(boost::math::complement(dist, std::abs(r.t))));
  r.valid = true;
  return r;
}

double t_quantile(double df, double probability) {
  return boost::math::quantile(boost::math::students_t(df), probability);
}

double f_quantile(double df1, double df2, double probability) {
  return boost::math::quantile(boost::math::fisher_f(df1, df2), probability);
}

}  // namespace bricklayer::study
