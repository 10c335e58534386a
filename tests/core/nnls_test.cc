// Lawson-Hanson NNLS against known answers and against brute force over every active set.
#include "bricklayer/core/nnls.h"

#include <algorithm>
#include <random>

#include <catch2/catch.hpp>

using namespace bricklayer::core;

namespace {

// Brute force: the best least-squares solution over every subset whose solution is nonnegative.
double brute_force_objective(const Eigen::MatrixXd& A, const Eigen::VectorXd& b) {
  const int n = static_cast<int>(A.cols());
  double best = b.squaredNorm();
  for (int mask = 1; mask < (1 << n); ++mask) {
    std::vector<int> cols;
    for (int j = 0; j < n; ++j) {
      if (mask & (1 << j)) cols.push_back(j);
    }
    Eigen::MatrixXd sub(A.rows(), static_cast<Eigen::Index>(cols.size()));
    for (size_t k = 0; k < cols.size(); ++k) sub.col(static_cast<Eigen::Index>(k)) = A.col(cols[k]);
    const Eigen::VectorXd s = sub.completeOrthogonalDecomposition().solve(b);
    if (s.minCoeff() < -1e-12) continue;
    best = std::min(best, (sub * s - b).squaredNorm());
  }
  return best;
}

}  // namespace

TEST_CASE("NNLS: an unconstrained optimum inside the orthant is returned exactly") {
  Eigen::MatrixXd A(3, 2);
  A << 1, 0, 0, 1, 1, 1;
  const Eigen::VectorXd x_true = Eigen::Vector2d(2.0, 3.0);
  const NnlsResult r = solve_nnls(A, A * x_true);
  REQUIRE(r.converged);
  CHECK(r.x(0) == Approx(2.0).epsilon(1e-12));
  CHECK(r.x(1) == Approx(3.0).epsilon(1e-12));
}

TEST_CASE("NNLS: a negative unconstrained optimum is clipped to the boundary") {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(2, 2);
  const NnlsResult r = solve_nnls(A, Eigen::Vector2d(-1.0, 4.0));
  REQUIRE(r.converged);
  CHECK(r.x(0) == 0.0);
  CHECK(r.x(1) == Approx(4.0));
}

TEST_CASE("NNLS: b = 0 and empty problems give x = 0") {
  const NnlsResult r = solve_nnls(Eigen::MatrixXd::Ones(3, 2), Eigen::VectorXd::Zero(3));
  CHECK(r.converged);
  CHECK(r.x.isZero());
  const NnlsResult e = solve_nnls(Eigen::MatrixXd(2, 0), Eigen::VectorXd::Ones(2));
  CHECK(e.converged);
  CHECK(e.x.size() == 0);
}

TEST_CASE("NNLS matches brute force on random (also rank-deficient) problems, dense, sparse and normal forms agree") {
  std::mt19937 rng(12345);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    const int m = 2 + trial % 5;
    const int n = 1 + trial % 7;
    Eigen::MatrixXd A(m, n);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < n; ++j) A(i, j) = normal(rng);
    if (trial % 3 == 0 && n >= 2) A.col(n - 1) = A.col(0) * 2.0;  // duplicate direction: rank deficient
    Eigen::VectorXd b(m);
    for (int i = 0; i < m; ++i) b(i) = normal(rng);
    const NnlsResult r = solve_nnls(A, b);
    INFO("trial " << trial);
    REQUIRE(r.converged);
    CHECK(r.x.minCoeff() >= 0.0);
    const double objective = (A * r.x - b).squaredNorm();
    CHECK(objective == Approx(brute_force_objective(A, b)).margin(1e-9));
    const Eigen::SparseMatrix<double> S = A.sparseView();
    CHECK((A * solve_nnls(S, b).x - b).squaredNorm() == Approx(objective).margin(1e-10));
    const Eigen::MatrixXd G = A.transpose() * A;
    const Eigen::VectorXd atb = A.transpose() * b;
    CHECK((A * solve_nnls_normal(G, atb).x - b).squaredNorm() == Approx(objective).margin(1e-10));
  }
}

TEST_CASE("NNLS reports non-convergence when the iteration limit is too small") {
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(4, 4);
  const NnlsResult r = solve_nnls(A, Eigen::Vector4d(1, 2, 3, 4), 2);
  CHECK_FALSE(r.converged);
  CHECK(r.iterations == 2);
  CHECK(r.x.minCoeff() >= 0.0);
}

TEST_CASE("NNLS warm starts: any initial passive set gives the optimum (sparse, banded updates)") {
  std::mt19937 rng(777);
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> pick(0, 1000);
  for (int trial = 0; trial < 300; ++trial) {
    const int m = 3 + trial % 6;
    const int n = 2 + trial % 9;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, n);
    for (int j = 0; j < n; ++j) {  // banded sparse columns, like contact rows
      for (int i = 0; i < m; ++i) {
        if (std::abs(i - j % m) <= 1) A(i, j) = normal(rng);
      }
    }
    if (trial % 4 == 0 && n >= 3) A.col(2) = A.col(1) * -0.5 + A.col(0);  // dependent
    Eigen::VectorXd b(m);
    for (int i = 0; i < m; ++i) b(i) = normal(rng);
    std::vector<int> initial;
    for (int j = 0; j < n; ++j) {
      if (pick(rng) % 2) initial.push_back(j);
    }
    std::shuffle(initial.begin(), initial.end(), rng);
    const Eigen::SparseMatrix<double> S = A.sparseView();
    const NnlsResult r = solve_nnls(S, b, 0, initial);
    INFO("trial " << trial);
    REQUIRE(r.converged);
    CHECK(r.x.minCoeff() >= 0.0);
    CHECK((A * r.x - b).squaredNorm() == Approx(brute_force_objective(A, b)).margin(1e-9));
  }
}

TEST_CASE("NNLS on larger banded problems satisfies the optimality (KKT) conditions") {
  // Long runs add and remove hundreds of indices, which widens the factor's bands and triggers rebuilds.
  std::mt19937 rng(4242);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 12; ++trial) {
    const int m = 150;
    const int n = 260;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, n);
    for (int j = 0; j < n; ++j) {
      const int centre = (j * m) / n;
      for (int i = std::max(0, centre - 2); i <= std::min(m - 1, centre + 2); ++i) A(i, j) = normal(rng);
    }
    Eigen::VectorXd b(m);
    for (int i = 0; i < m; ++i) b(i) = normal(rng) + (trial % 2 ? 2.0 : 0.0);
    std::vector<int> initial;
    for (int j = 0; j < n; j += 2) initial.push_back(j);
    const Eigen::SparseMatrix<double> S = A.sparseView();
    const NnlsResult r = solve_nnls(S, b, 0, trial % 3 == 0 ? std::vector<int>{} : initial);
    INFO("trial " << trial << ", iterations " << r.iterations);
    REQUIRE(r.converged);
    const Eigen::VectorXd w = A.transpose() * (b - A * r.x);
    CHECK(r.x.minCoeff() >= 0.0);
    for (int j = 0; j < n; ++j) {
      if (r.x(j) > 0.0) {
        CHECK(std::abs(w(j)) < 1e-8);  // stationary on the positive set
      } else {
        CHECK(w(j) < 1e-8);  // no descent direction into the orthant
      }
    }
  }
}
