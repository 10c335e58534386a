#include "bricklayer/core/dynamics.h"

#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/SparseCore>

#include "bricklayer/core/nnls.h"
#include "bricklayer/core/program.h"

namespace bricklayer::core {

QpMethod parse_qp_method(const std::string& name) {
  if (name == "nnls") return QpMethod::kNnls;
  if (name == "nlopt") return QpMethod::kNlopt;
  throw std::invalid_argument("unknown QP method \"" + name + "\" (expected nnls or nlopt)");
}

std::string to_string(QpMethod method) { return method == QpMethod::kNnls ? "nnls" : "nlopt"; }

bool Accelerations::moving(size_t i) const {
  return std::abs(a[i]) + 0.5 * std::abs(alpha[i]) > kAccelerationTolerance;
}

bool Accelerations::any_moving() const {
  for (size_t i = 0; i < a.size(); ++i) {
    if (moving(i)) return true;
  }
  return false;
}

namespace {

// The contact rows of the QP: one per contact end, J z >= 0, over the free blocks' (a, alpha).
struct ContactRows {
  std::vector<int> var;        // block index -> first variable (2 per free block), -1 when fixed
  int num_vars = 0;
  struct Term {
    int var;
    double value;
  };
  std::vector<std::array<Term, 4>> rows;  // unused terms have var = -1
  std::vector<int> contact_end;           // 2 * contact + (0 left, 1 right)
};

ContactRows contact_rows(const ContactGraph& g, const std::vector<char>& free) {
  ContactRows c;
  const size_t n = g.size();
  c.var.assign(n, -1);
  for (size_t i = 0; i < n; ++i) {
    if (free.empty() || free[i]) {
      c.var[i] = c.num_vars;
      c.num_vars += 2;
    }
  }
  for (size_t k = 0; k < g.contacts.size(); ++k) {
    const Contact& ct = g.contacts[k];
    const int vu = c.var[static_cast<size_t>(ct.upper)];
    if (vu < 0) continue;  // upper block fixed: the contact cannot constrain anything free
    const int vl = ct.lower == kSurface ? -1 : c.var[static_cast<size_t>(ct.lower)];
    for (int end = 0; end < 2; ++end) {
      const double p = end == 0 ? ct.left : ct.right;
      std::array<ContactRows::Term, 4> row{{{vu, 1.0}, {vu + 1, p - g.centre(ct.upper)}, {-1, 0.0}, {-1, 0.0}}};
      if (vl >= 0) {
        row[2] = {vl, -1.0};
        row[3] = {vl + 1, -(p - g.centre(ct.lower))};
      }
      c.rows.push_back(row);
      c.contact_end.push_back(static_cast<int>(2 * k) + end);
    }
  }
  return c;
}

Accelerations by_nnls(const ContactGraph& g, const ContactRows& c, const std::vector<double>* warm) {
  const double inertia = (1.0 + g.height * g.height) / 12.0;
  const double inv_sqrt_inertia = 1.0 / std::sqrt(inertia);
  // A = M^-1/2 J^T (variables x contact ends), b = -M^1/2 z0 = (1, 0, 1, 0, ...).
  const int m = static_cast<int>(c.rows.size());
  if (m == 0) {  // nothing supports any free block: free fall
    Accelerations fall;
    fall.a.assign(g.size(), 0.0);
    fall.alpha.assign(g.size(), 0.0);
    fall.force.assign(2 * g.contacts.size(), 0.0);
    for (size_t i = 0; i < g.size(); ++i) {
      if (c.var[i] >= 0) fall.a[i] = -1.0;
    }
    return fall;
  }
  Eigen::SparseMatrix<double> A(c.num_vars, m);
  A.reserve(Eigen::VectorXi::Constant(m, 4));
  for (int k = 0; k < m; ++k) {
    for (const auto& t : c.rows[static_cast<size_t>(k)]) {
      if (t.var < 0) continue;
      A.insert(t.var, k) = (t.var % 2 == 0) ? t.value : t.value * inv_sqrt_inertia;
    }
  }
  A.makeCompressed();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(c.num_vars);
  for (int v = 0; v < c.num_vars; v += 2) b(v) = 1.0;
  // Warm start: the two extreme support ends of every free block, top row first (see two_point_certificate).
  std::vector<int> column_of(2 * g.contacts.size(), -1);
  for (int k = 0; k < m; ++k) column_of[static_cast<size_t>(c.contact_end[static_cast<size_t>(k)])] = k;
  std::vector<int> initial;
  initial.reserve(static_cast<size_t>(c.num_vars));
  for (int row = g.num_rows() - 1; row >= 0; --row) {
    for (int i : g.rows[static_cast<size_t>(row)]) {
      const auto& sup = g.supports[static_cast<size_t>(i)];
      if (c.var[static_cast<size_t>(i)] < 0 || sup.empty()) continue;
      bool seeded = false;
      if (warm != nullptr && warm->size() == 2 * g.contacts.size()) {
        for (int k : sup) {
          for (size_t end = 0; end < 2; ++end) {
            if ((*warm)[2 * static_cast<size_t>(k) + end] > 0.0) {
              initial.push_back(column_of[2 * static_cast<size_t>(k) + end]);
              seeded = true;
            }
          }
        }
      }
      if (seeded) continue;
      initial.push_back(column_of[2 * static_cast<size_t>(sup.front())]);
      initial.push_back(column_of[2 * static_cast<size_t>(sup.back()) + 1]);
    }
  }
  NnlsResult nnls = solve_nnls(A, b, 0, initial);
  if (!nnls.converged) nnls = solve_nnls(A, b, 20 * m + 100);  // cold start with a generous limit
  if (!nnls.converged) {
    throw std::runtime_error("exact annotator QP (nnls): no convergence after " + std::to_string(nnls.iterations) +
                             " iterations");
  }
  // z = z0 + M^-1 J^T lambda = M^-1/2 (A lambda - b)
  const Eigen::VectorXd r = A * nnls.x - b;
  Accelerations out;
  out.a.assign(g.size(), 0.0);
  out.alpha.assign(g.size(), 0.0);
  out.force.assign(2 * g.contacts.size(), 0.0);
  for (size_t i = 0; i < g.size(); ++i) {
    const int v = c.var[i];
    if (v < 0) continue;
    out.a[i] = r(v);
    out.alpha[i] = r(v + 1) * inv_sqrt_inertia;
  }
  for (int k = 0; k < m; ++k) out.force[static_cast<size_t>(c.contact_end[static_cast<size_t>(k)])] = nnls.x(k);
  out.converged = nnls.converged;
  out.iterations = nnls.iterations;
  return out;
}

Accelerations by_nlopt(const ContactGraph& g, const ContactRows& c) {
  const double inertia = (1.0 + g.height * g.height) / 12.0;
  opt::Problem problem;
  // minimise 1/2 (a+1)^2 + 1/2 I alpha^2 = 1/2 a^2 + a + 1/2 I alpha^2 + const
  for (int v = 0; v < c.num_vars; v += 2) {
    problem.add_variable(-opt::kInfinity, opt::kInfinity, 1.0);
    problem.add_variable(-opt::kInfinity, opt::kInfinity, 0.0);
    problem.add_quadratic(v, v, 1.0);
    problem.add_quadratic(v + 1, v + 1, inertia);
  }
  for (const auto& row : c.rows) {
    const int r = problem.add_row(0.0, opt::kInfinity);
    for (const auto& t : row) {
      if (t.var >= 0) problem.set(r, t.var, t.value);
    }
  }
  opt::SolverOptions options;
  options.feasibility_tolerance = 1e-9;
  const opt::SolveResult result = opt::make_solver("nlopt")->solve(problem, options);
  if (result.status != opt::SolveStatus::kOptimal) {
    throw std::runtime_error("exact annotator QP (nlopt): " + opt::to_string(result.status) + ": " + result.message);
  }
  Accelerations out;
  out.a.assign(g.size(), 0.0);
  out.alpha.assign(g.size(), 0.0);
  for (size_t i = 0; i < g.size(); ++i) {
    const int v = c.var[i];
    if (v < 0) continue;
    out.a[i] = result.x[static_cast<size_t>(v)] + 0.0;
    out.alpha[i] = result.x[static_cast<size_t>(v) + 1];
  }
  return out;
}

}  // namespace

namespace {

// One top-down statics pass. kHull: each block rests on the two extreme ends of its support hull. kCentred:
// each block picks, among all pairs of its contact ends that carry its load with nonnegative forces, the pair
// that puts the load closest to the middle of each lower block's own support hull (keeping lower blocks
// stable). Either succeeding proves balance.
enum class Split { kHull, kCentred };

bool statics_pass(const ContactGraph& g, const std::vector<char>& free, Split split, std::vector<double>& f) {
  f.assign(2 * g.contacts.size(), 0.0);
  auto is_free = [&](int i) { return free.empty() || free[static_cast<size_t>(i)] != 0; };
  auto hull_middle = [&](int block, double& middle) {
    const auto& sup = g.supports[static_cast<size_t>(block)];
    if (sup.empty()) return false;
    middle = 0.5 * (g.contacts[static_cast<size_t>(sup.front())].left + g.contacts[static_cast<size_t>(sup.back())].right);
    return true;
  };
  for (int r = g.num_rows() - 1; r >= 0; --r) {
    for (int i : g.rows[static_cast<size_t>(r)]) {
      if (!is_free(i)) continue;
      const double c = g.centre(i);
      double load = 1.0;  // own weight
      double moment = 0.0;
      for (int k : g.carries[static_cast<size_t>(i)]) {
        const Contact& ct = g.contacts[static_cast<size_t>(k)];
        if (!is_free(ct.upper)) continue;
        const double fl = f[2 * static_cast<size_t>(k)];
        const double fr = f[2 * static_cast<size_t>(k) + 1];
        load += fl + fr;
        moment += fl * (ct.left - c) + fr * (ct.right - c);
      }
      const auto& sup = g.supports[static_cast<size_t>(i)];
      if (sup.empty()) return false;
      const double tol = -1e-9 * load;
      // Forces at contact ends e1 (position p1) and e2 (p2 > p1) carrying (load, moment).
      auto split_at = [&](double p1, double p2, double& f1, double& f2) {
        const double d1 = p1 - c;
        const double d2 = p2 - c;
        if (!(d2 - d1 > kContactTolerance)) return false;
        f2 = (moment - load * d1) / (d2 - d1);
        f1 = load - f2;
        return f1 >= tol && f2 >= tol;
      };
      if (split == Split::kHull) {
        const int kl = sup.front();
        const int kr = sup.back();
        double fl = 0.0;
        double fr = 0.0;
        if (!split_at(g.contacts[static_cast<size_t>(kl)].left, g.contacts[static_cast<size_t>(kr)].right, fl, fr)) {
          return false;
        }
        f[2 * static_cast<size_t>(kl)] = std::max(0.0, fl);
        f[2 * static_cast<size_t>(kr) + 1] = std::max(0.0, fr);
        continue;
      }
      size_t best1 = 0;
      size_t best2 = 0;
      double best_f1 = 0.0;
      double best_f2 = 0.0;
      double best_score = std::numeric_limits<double>::infinity();
      const size_t ends = 2 * sup.size();
      auto end_position = [&](size_t e) {
        const Contact& ct = g.contacts[static_cast<size_t>(sup[e / 2])];
        return e % 2 == 0 ? ct.left : ct.right;
      };
      auto end_cost = [&](size_t e) {  // distance of the end from the middle of the lower block's support
        const Contact& ct = g.contacts[static_cast<size_t>(sup[e / 2])];
        if (ct.lower == kSurface || !is_free(ct.lower)) return 0.0;
        double middle = 0.0;
        if (!hull_middle(ct.lower, middle)) return 1e3;
        return std::abs(end_position(e) - middle);
      };
      for (size_t e1 = 0; e1 < ends; ++e1) {
        for (size_t e2 = e1 + 1; e2 < ends; ++e2) {
          double f1 = 0.0;
          double f2 = 0.0;
          if (!split_at(end_position(e1), end_position(e2), f1, f2)) continue;
          const double score = f1 * end_cost(e1) + f2 * end_cost(e2);
          if (score < best_score) {
            best_score = score;
            best1 = e1;
            best2 = e2;
            best_f1 = f1;
            best_f2 = f2;
          }
        }
      }
      if (!std::isfinite(best_score)) return false;
      f[2 * static_cast<size_t>(sup[best1 / 2]) + best1 % 2] += std::max(0.0, best_f1);
      f[2 * static_cast<size_t>(sup[best2 / 2]) + best2 % 2] += std::max(0.0, best_f2);
    }
  }
  return true;
}

}  // namespace

bool two_point_certificate(const ContactGraph& g, const std::vector<char>& free, std::vector<double>* forces) {
  std::vector<double> local;
  std::vector<double>& f = forces ? *forces : local;
  return statics_pass(g, free, Split::kHull, f) || statics_pass(g, free, Split::kCentred, f);
}

Accelerations initial_accelerations(const ContactGraph& graph, const std::vector<char>& free, QpMethod method,
                                    bool certificate, const std::vector<double>* warm_forces) {
  if (!free.empty() && free.size() != graph.size()) throw std::invalid_argument("free: one flag per block expected");
  if (certificate) {
    Accelerations rest;
    if (two_point_certificate(graph, free, &rest.force)) {
      rest.a.assign(graph.size(), 0.0);
      rest.alpha.assign(graph.size(), 0.0);
      rest.certified = true;
      return rest;
    }
  }
  const ContactRows rows = contact_rows(graph, free);
  if (rows.num_vars == 0) {
    Accelerations none;
    none.a.assign(graph.size(), 0.0);
    none.alpha.assign(graph.size(), 0.0);
    none.force.assign(2 * graph.contacts.size(), 0.0);
    return none;
  }
  return method == QpMethod::kNnls ? by_nnls(graph, rows, warm_forces) : by_nlopt(graph, rows);
}

}  // namespace bricklayer::core
