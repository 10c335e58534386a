// Non-negative least squares (Lawson & Hanson's active-set method, "Solving Least Squares Problems",
// 1974, ch. 23): minimise ||A x - b|| subject to x >= 0. Exact in finitely many steps; the passive-set
// least-squares problems are solved by a Cholesky factorisation of the Gram matrix that is updated (not
// recomputed) when one index enters or leaves the passive set.
#pragma once

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <vector>

namespace bricklayer::core {

struct NnlsResult {
  Eigen::VectorXd x;
  int iterations = 0;      // outer iterations (indices moved into the passive set)
  bool converged = false;  // false when max_iterations was reached (x is then feasible but not optimal)
};

// max_iterations 0 means 3 * number of columns.
NnlsResult solve_nnls(const Eigen::MatrixXd& A, const Eigen::VectorXd& b, int max_iterations = 0);

// The same problem given by its normal equations: gram = A^T A (symmetric positive semidefinite) and
// atb = A^T b. Lets a caller build A^T A from sparse structure without forming A.
NnlsResult solve_nnls_normal(const Eigen::MatrixXd& gram, const Eigen::VectorXd& atb, int max_iterations = 0);

// The same with A sparse (column-major): Gram entries are formed on demand, never the whole A^T A.
// initial_passive: a warm start (a guess of the columns with positive x at the optimum). Any guess is safe:
// dependent columns are skipped and columns with a non-positive least-squares value dropped before the
// usual iterations; a good guess leaves only a few. Order it so that columns sharing rows of A are close
// together (the Cholesky update then only touches a band).
NnlsResult solve_nnls(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b, int max_iterations = 0,
                      const std::vector<int>& initial_passive = {});

}  // namespace bricklayer::core
