#include "bricklayer/core/nnls.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/SparseCore>

namespace bricklayer::core {
namespace {

// Cholesky factor L (lower) of gram restricted to an ordered passive set, stored by bands: row t holds
// columns [start_[t], t] only, and every operation touches only those bands, so adding or removing an index
// costs O(p * band) time and the factor O(p * band) memory when neighbouring columns sit close together.
template <class Ops>
class PassiveCholesky {
 public:
  // capacity: the largest possible passive set (rank of A <= its number of rows).
  PassiveCholesky(const Ops& ops, int columns, int capacity)
      : ops_(ops), capacity_(capacity), position_(static_cast<size_t>(columns), -1), work_(capacity) {}

  const std::vector<int>& indices() const { return passive_; }
  int size() const { return static_cast<int>(passive_.size()); }

  // Appends index j; false (and nothing changes) when its column is numerically dependent on the passive ones.
  bool add(int j) {
    const int p = size();
    if (p >= capacity_) return false;  // more columns than rows: j is necessarily dependent
    const double gjj = ops_.gram(j, j);
    if (!(gjj > 0.0)) return false;
    // G_Pj is nonzero only for passive columns that share a row of A with j.
    int first = p;
    touched_.clear();
    ops_.for_each_neighbour(j, [&](int other) {
      const int q = position_[static_cast<size_t>(other)];
      if (q < 0) return;
      touched_.push_back(q);
      first = std::min(first, q);
    });
    for (int t = first; t < p; ++t) work_(t) = 0.0;
    for (int q : touched_) work_(q) = ops_.gram(passive_[static_cast<size_t>(q)], j);
    // Forward substitution from the first nonzero: entries before it stay zero.
    for (int t = first; t < p; ++t) {
      const std::vector<double>& row = rows_[static_cast<size_t>(t)];
      const int st = start_[static_cast<size_t>(t)];
      double v = work_(t);
      for (int k = std::max(st, first); k < t; ++k) v -= row[static_cast<size_t>(k - st)] * work_(k);
      work_(t) = v / row.back();
    }
    double d = gjj;
    for (int t = first; t < p; ++t) d -= work_(t) * work_(t);
    if (!(d > 1e-12 * gjj)) return false;
    std::vector<double> row(static_cast<size_t>(p - first + 1));
    for (int t = first; t < p; ++t) row[static_cast<size_t>(t - first)] = work_(t);
    row.back() = std::sqrt(d);
    rows_.push_back(std::move(row));
    start_.push_back(first);
    position_[static_cast<size_t>(j)] = p;
    passive_.push_back(j);
    return true;
  }

  // Removes the passive index at position k and restores the triangle with Givens rotations.
  void remove_at(int k) {
    const int p = size();
    rows_.erase(rows_.begin() + k);
    start_.erase(start_.begin() + k);
    // Row r (now k..p-2) ends one column right of the diagonal. Rotations on columns (i, i+1), i = k..p-2,
    // move it back; a rotation touches only rows whose band reaches column i + 1, and a row whose band
    // starts at i + 1 grows by one column to the left.
    const int rows = p - 1;
    buckets_.assign(static_cast<size_t>(p + 1), {});
    active_.clear();
    for (int r = k; r < rows; ++r) {
      const int s = start_[static_cast<size_t>(r)];
      if (s <= k + 1) {
        if (s == k + 1) grow_left(r);
        active_.push_back(r);
      } else {
        buckets_[static_cast<size_t>(s)].push_back(r);
      }
    }
    for (int i = k; i < rows; ++i) {
      for (int r : buckets_[static_cast<size_t>(i + 1)]) {
        grow_left(r);
        active_.push_back(r);
      }
      const double a = at(i, i);
      const double b = at(i, i + 1);
      const double norm = std::hypot(a, b);
      if (norm != 0.0) {
        const double c = a / norm;
        const double sn = b / norm;
        for (int r : active_) {
          if (r < i) continue;
          const double u = at(r, i);
          const double v = at(r, i + 1);
          at(r, i) = c * u + sn * v;
          at(r, i + 1) = -sn * u + c * v;
        }
      }
      rows_[static_cast<size_t>(i)].pop_back();  // (i, i+1) is now zero: row i ends at its diagonal
      active_.erase(std::remove_if(active_.begin(), active_.end(), [&](int r) { return r <= i; }), active_.end());
    }
    position_[static_cast<size_t>(passive_[static_cast<size_t>(k)])] = -1;
    passive_.erase(passive_.begin() + k);
    for (int t = k; t < rows; ++t) position_[static_cast<size_t>(passive_[static_cast<size_t>(t)])] = t;
  }

  // Number of stored entries of L (sum of the bands).
  size_t cells() const {
    size_t total = 0;
    for (const auto& row : rows_) total += row.size();
    return total;
  }

  // Refactors with the passive set in ascending column order (the caller's natural, banded order): indices
  // appended by the iterations and Givens removals widen the bands over time. Returns the indices that could
  // not be re-added (numerically dependent), which are no longer passive.
  std::vector<int> rebuild() {
    std::vector<int> order = passive_;
    std::sort(order.begin(), order.end());
    for (int j : passive_) position_[static_cast<size_t>(j)] = -1;
    passive_.clear();
    rows_.clear();
    start_.clear();
    std::vector<int> dropped;
    for (int j : order) {
      if (!add(j)) dropped.push_back(j);
    }
    return dropped;
  }

  // Solves gram_PP s = rhs_P with two banded triangular solves.
  Eigen::VectorXd solve(const Eigen::VectorXd& rhs) const {
    const int p = size();
    Eigen::VectorXd y(p);
    for (int t = 0; t < p; ++t) {
      const std::vector<double>& row = rows_[static_cast<size_t>(t)];
      const int st = start_[static_cast<size_t>(t)];
      double v = rhs(passive_[static_cast<size_t>(t)]);
      for (int c = st; c < t; ++c) v -= row[static_cast<size_t>(c - st)] * y(c);
      y(t) = v / row.back();
    }
    for (int t = p - 1; t >= 0; --t) {
      const std::vector<double>& row = rows_[static_cast<size_t>(t)];
      const int st = start_[static_cast<size_t>(t)];
      y(t) /= row.back();
      const double yt = y(t);
      for (int c = st; c < t; ++c) y(c) -= row[static_cast<size_t>(c - st)] * yt;
    }
    return y;
  }

 private:
  double& at(int r, int c) { return rows_[static_cast<size_t>(r)][static_cast<size_t>(c - start_[static_cast<size_t>(r)])]; }
  void grow_left(int r) {
    auto& row = rows_[static_cast<size_t>(r)];
    row.insert(row.begin(), 0.0);
    --start_[static_cast<size_t>(r)];
  }

  const Ops& ops_;
  int capacity_;
  std::vector<std::vector<double>> rows_;  // rows_[t][c - start_[t]] = L(t, c)
  std::vector<int> start_;                 // first column of each row's band
  std::vector<int> position_;              // column -> position in passive_, or -1
  std::vector<int> passive_;
  Eigen::VectorXd work_;
  std::vector<int> touched_;
  std::vector<std::vector<int>> buckets_;
  std::vector<int> active_;
};

// Ops: gram(i, j) = (A^T A)_ij, gradient(x) = A^T (b - A x), atb() = A^T b, max_gram_diagonal().
template <class Ops>
NnlsResult lawson_hanson(const Ops& ops, int max_iterations, const std::vector<int>& initial) {
  const Eigen::VectorXd& atb = ops.atb();
  const int n = static_cast<int>(atb.size());
  NnlsResult result;
  result.x = Eigen::VectorXd::Zero(n);
  if (n == 0) {
    result.converged = true;
    return result;
  }
  if (max_iterations <= 0) max_iterations = 3 * n;
  const double scale = std::max(1.0, atb.cwiseAbs().maxCoeff()) * std::max(1.0, ops.max_gram_diagonal());
  const double tol = 1e-11 * scale;

  PassiveCholesky<Ops> chol(ops, n, std::min(n, ops.rank_bound()));
  std::vector<char> in_passive(static_cast<size_t>(n), 0);
  std::vector<char> rejected(static_cast<size_t>(n), 0);
  Eigen::VectorXd& x = result.x;
  Eigen::VectorXd w = atb;  // gradient of -1/2||Ax-b||^2 at x = 0

  // Warm start: take the initial passive set (dependent columns skipped) and drop every index whose
  // least-squares value is not positive until all are (LH's inner loop from x = 0, where every step
  // length is 0). The invariants of the main loop then hold: x >= 0, x_P solves the passive problem.
  if (!initial.empty()) {
    for (int j : initial) {
      if (j >= 0 && j < n && !in_passive[static_cast<size_t>(j)] && chol.add(j)) in_passive[static_cast<size_t>(j)] = 1;
    }
    while (chol.size() > 0) {
      const Eigen::VectorXd s = chol.solve(atb);
      bool removed = false;
      for (int k = chol.size() - 1; k >= 0; --k) {
        if (s(k) <= 0.0) {
          in_passive[static_cast<size_t>(chol.indices()[static_cast<size_t>(k)])] = 0;
          chol.remove_at(k);
          removed = true;
        }
      }
      if (!removed) {
        for (int k = 0; k < chol.size(); ++k) x(chol.indices()[static_cast<size_t>(k)]) = s(k);
        break;
      }
    }
    w = ops.gradient(x);
  }
  size_t rebuild_at = 3 * chol.cells() + 64 * static_cast<size_t>(chol.size()) + 1024;

  while (result.iterations < max_iterations) {
    int best = -1;
    double best_w = tol;
    for (int j = 0; j < n; ++j) {
      if (!in_passive[static_cast<size_t>(j)] && !rejected[static_cast<size_t>(j)] && w(j) > best_w) {
        best_w = w(j);
        best = j;
      }
    }
    if (best < 0) {
      result.converged = true;
      break;
    }
    ++result.iterations;
    if (!chol.add(best)) {
      rejected[static_cast<size_t>(best)] = 1;  // dependent column: its gradient is rounding noise
      continue;
    }
    in_passive[static_cast<size_t>(best)] = 1;
    std::fill(rejected.begin(), rejected.end(), 0);

    Eigen::VectorXd s = chol.solve(atb);
    // Inner loop: step back towards x until every passive variable is positive.
    int guard = 0;
    while (true) {
      const auto& passive = chol.indices();
      double alpha = 2.0;
      for (int k = 0; k < chol.size(); ++k) {
        if (s(k) <= 0.0) {
          const double xk = x(passive[static_cast<size_t>(k)]);
          const double a = xk / (xk - s(k));
          alpha = std::min(alpha, a);
        }
      }
      if (alpha > 1.0) break;
      if (++guard > 3 * n) break;  // cannot happen in exact arithmetic
      for (int k = 0; k < chol.size(); ++k) {
        const int j = passive[static_cast<size_t>(k)];
        x(j) += alpha * (s(k) - x(j));
      }
      // Move every passive variable that reached zero (at least the blocking one) to the zero set.
      bool removed = false;
      for (int k = chol.size() - 1; k >= 0; --k) {
        const int j = chol.indices()[static_cast<size_t>(k)];
        if (x(j) <= 1e-15 * scale || (s(k) <= 0.0 && x(j) <= 1e-12 * scale)) {
          x(j) = 0.0;
          in_passive[static_cast<size_t>(j)] = 0;
          chol.remove_at(k);
          removed = true;
        }
      }
      if (!removed) {
        // Rounding: remove the blocking index explicitly.
        int worst = 0;
        double worst_ratio = 2.0;
        for (int k = 0; k < chol.size(); ++k) {
          if (s(k) <= 0.0) {
            const double xk = x(chol.indices()[static_cast<size_t>(k)]);
            const double a = xk / (xk - s(k));
            if (a < worst_ratio) worst_ratio = a, worst = k;
          }
        }
        const int j = chol.indices()[static_cast<size_t>(worst)];
        x(j) = 0.0;
        in_passive[static_cast<size_t>(j)] = 0;
        chol.remove_at(worst);
      }
      s = chol.solve(atb);
    }
    for (int k = 0; k < chol.size(); ++k) x(chol.indices()[static_cast<size_t>(k)]) = std::max(0.0, s(k));
    if (chol.cells() > rebuild_at) {
      for (int j : chol.rebuild()) {
        x(j) = 0.0;
        in_passive[static_cast<size_t>(j)] = 0;
      }
      rebuild_at = 3 * chol.cells() + 64 * static_cast<size_t>(chol.size()) + 1024;
    }
    w = ops.gradient(x);
  }
  return result;
}

struct DenseOps {
  const Eigen::MatrixXd& g;
  const Eigen::VectorXd& ab;
  double gram(int i, int j) const { return g(i, j); }
  const Eigen::VectorXd& atb() const { return ab; }
  Eigen::VectorXd gradient(const Eigen::VectorXd& x) const { return ab - g * x; }
  double max_gram_diagonal() const { return g.diagonal().maxCoeff(); }
  int rank_bound() const { return static_cast<int>(g.rows()); }
  template <class F>
  void for_each_neighbour(int j, F f) const {
    for (int o = 0; o < g.rows(); ++o) {
      if (o != j) f(o);
    }
  }
};

struct SparseOps {
  const Eigen::SparseMatrix<double>& a;  // column-major
  const Eigen::VectorXd& b;
  Eigen::VectorXd ab;
  Eigen::SparseMatrix<double> at;  // A^T, column-major: the columns of A that use each row
  SparseOps(const Eigen::SparseMatrix<double>& a_, const Eigen::VectorXd& b_)
      : a(a_), b(b_), ab(a_.transpose() * b_), at(a_.transpose()) {}
  template <class F>
  void for_each_neighbour(int j, F f) const {
    for (Eigen::SparseMatrix<double>::InnerIterator row(a, j); row; ++row) {
      for (Eigen::SparseMatrix<double>::InnerIterator col(at, static_cast<int>(row.row())); col; ++col) {
        if (col.row() != j) f(static_cast<int>(col.row()));
      }
    }
  }
  double gram(int i, int j) const {
    Eigen::SparseMatrix<double>::InnerIterator p(a, i), q(a, j);
    double sum = 0.0;
    while (p && q) {
      if (p.row() == q.row()) {
        sum += p.value() * q.value();
        ++p;
        ++q;
      } else if (p.row() < q.row()) {
        ++p;
      } else {
        ++q;
      }
    }
    return sum;
  }
  const Eigen::VectorXd& atb() const { return ab; }
  Eigen::VectorXd gradient(const Eigen::VectorXd& x) const {
    const Eigen::VectorXd r = b - a * x;
    return a.transpose() * r;
  }
  int rank_bound() const { return static_cast<int>(a.rows()); }
  double max_gram_diagonal() const {
    double best = 0.0;
    for (int j = 0; j < a.cols(); ++j) best = std::max(best, a.col(j).squaredNorm());
    return best;
  }
};

}  // namespace

NnlsResult solve_nnls_normal(const Eigen::MatrixXd& gram, const Eigen::VectorXd& atb, int max_iterations) {
  return lawson_hanson(DenseOps{gram, atb}, max_iterations, {});
}

NnlsResult solve_nnls(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b, int max_iterations,
                      const std::vector<int>& initial_passive) {
  return lawson_hanson(SparseOps(A, b), max_iterations, initial_passive);
}

NnlsResult solve_nnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int max_iterations) {
  const Eigen::MatrixXd gram = A.transpose() * A;
  const Eigen::VectorXd atb = A.transpose() * b;
  return solve_nnls_normal(gram, atb, max_iterations);
}

}  // namespace bricklayer::core
