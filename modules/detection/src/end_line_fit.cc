#include "bricklayer/detection/end_line_fit.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <opencv2/core/optim.hpp>

namespace bricklayer::detection {
namespace {

constexpr double kMinSigma = 0.15, kMaxSigma = 4.0;  // pixels: sharper than the pixel grid, blurrier than any usable frame

// The unit step at 0 blurred by a Gaussian of width sigma, sampled at x.
double blurred_step(double x, double sigma) { return 0.5 * std::erfc(-x / (std::sqrt(2.0) * sigma)); }

// Residual sum of squares of the best levels for a centre and blur (variable projection), and those levels.
class Model : public cv::MinProblemSolver::Function {
 public:
  Model(const std::vector<float>& profile, const std::vector<float>& leakage, int first, int last, double line_width, double guess)
      : w_(line_width), guess_(guess), leakage_(leakage), a_(last - first + 1, 4), y_(last - first + 1), target_(last - first + 1) {
    for (int i = first; i <= last; ++i) {
      x_.push_back(i);
      y_(i - first) = profile[static_cast<size_t>(i)];
    }
  }
  int getDims() const override { return 2; }
  // v = (centre - guess, log sigma); outside the searched ranges the residual is made large, not clipped,
  // so the simplex walks back.
  double calc(const double* v) const override {
    const double sigma = std::exp(v[1]);
    double penalty = 0;
    if (sigma < kMinSigma) penalty += 1e6 * (kMinSigma - sigma);
    if (sigma > kMaxSigma) penalty += 1e6 * (sigma - kMaxSigma);
    if (std::abs(v[0]) > 2.5) penalty += 1e6 * (std::abs(v[0]) - 2.5);
    return rss(guess_ + v[0], std::clamp(sigma, kMinSigma, kMaxSigma), nullptr) + penalty;
  }
  double rss(double centre, double sigma, Eigen::Vector4d* levels) const {
    // The projector's light as the camera saw it: its prediction (sharp, each sample the level over its
    // pixel) blurred like the frame, taken off the profile.
    target_ = y_;
    if (!leakage_.empty()) {
      const int reach = static_cast<int>(std::ceil(4 * sigma)) + 1, n = static_cast<int>(leakage_.size());
      for (size_t k = 0; k < x_.size(); ++k) {
        double light = 0;
        for (int j = std::max(0, static_cast<int>(x_[k]) - reach); j <= std::min(n - 1, static_cast<int>(x_[k]) + reach); ++j)
          light += leakage_[static_cast<size_t>(j)] * (blurred_step(x_[k] - j + 0.5, sigma) - blurred_step(x_[k] - j - 0.5, sigma));
        target_(static_cast<Eigen::Index>(k)) -= light;
      }
    }
    for (size_t k = 0; k < x_.size(); ++k) {
      const double x = x_[k];
      a_(static_cast<Eigen::Index>(k), 0) = 1.0;
      a_(static_cast<Eigen::Index>(k), 1) = blurred_step(x - (centre - 0.5 * w_), sigma);
      a_(static_cast<Eigen::Index>(k), 2) = blurred_step(x - (centre + 0.5 * w_), sigma);
      a_(static_cast<Eigen::Index>(k), 3) = x - centre;
    }
    const Eigen::Vector4d p = a_.colPivHouseholderQr().solve(target_);
    if (levels) *levels = p;
    return (a_ * p - target_).squaredNorm();
  }
  size_t samples() const { return x_.size(); }

 private:
  double w_, guess_;
  const std::vector<float>& leakage_;
  std::vector<double> x_;
  mutable Eigen::MatrixXd a_;
  Eigen::VectorXd y_;
  mutable Eigen::VectorXd target_;
};

}  // namespace

std::optional<EndLineFit> fit_end_line(const std::vector<float>& profile, const std::vector<float>& leakage, double guess,
                                       double line_width, double half_window) {
  const int n = static_cast<int>(profile.size());
  if (!std::isfinite(guess) || !(line_width > 0) || !(half_window > 0)) return std::nullopt;
  if (!leakage.empty() && leakage.size() != profile.size()) return std::nullopt;
  const int first = static_cast<int>(std::ceil(guess - half_window)), last = static_cast<int>(std::floor(guess + half_window));
  // Enough samples for four levels and two searched terms with some to spare.
  if (first < 0 || last >= n || last - first + 1 < 9) return std::nullopt;
  const cv::Ptr<Model> model = cv::makePtr<Model>(profile, leakage, first, last, line_width, guess);
  const cv::Ptr<cv::DownhillSolver> solver =
      cv::DownhillSolver::create(model, cv::Mat(cv::Matx12d(0.5, 0.4)), cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, 400, 1e-10));
  // Start from the guess and a blur of about a pixel; twice, from the first answer, so a simplex that
  // collapsed early gets a fresh one.
  cv::Mat v = (cv::Mat_<double>(1, 2) << 0.0, 0.0);
  solver->minimize(v);
  solver->setInitStep(cv::Mat(cv::Matx12d(0.2, 0.2)));
  solver->minimize(v);
  const double offset = v.at<double>(0), sigma = std::exp(v.at<double>(1));
  if (std::abs(offset) > 2.0 || sigma < kMinSigma || sigma > kMaxSigma) return std::nullopt;
  Eigen::Vector4d p;
  const double rss = model->rss(guess + offset, sigma, &p);
  // Outside p0, on the line p0 + p1, inside p0 + p1 + p2: the line must be darker than both sides.
  const double outside = p(0), line = p(0) + p(1), inside = p(0) + p(1) + p(2);
  if (!(line < outside && line < inside)) return std::nullopt;
  EndLineFit fit;
  fit.centre = guess + offset;
  fit.sigma = sigma;
  fit.depth = 0.5 * (outside + inside) - line;
  fit.rms = std::sqrt(rss / static_cast<double>(model->samples()));
  return fit;
}

}  // namespace bricklayer::detection
