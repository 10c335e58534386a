// Initial accelerations of a pile released from rest (Roete & Zwick's model, DESIGN.md "The physics"):
// minimise sum_i 1/2 (a_i + g)^2 + 1/2 I alpha_i^2 subject to non-penetration at both ends of every
// contact interval. Units: g = 1, block length 1, unit mass, I = (1 + h^2) / 12.
#pragma once

#include <string>
#include <vector>

#include "bricklayer/core/contacts.h"

namespace bricklayer::core {

// A block moves when some point of it accelerates vertically by more than this (units of g):
// |a| + |alpha| / 2 > kAccelerationTolerance. See modules/core/README.md "Tolerance policy".
inline constexpr double kAccelerationTolerance = 1e-6;

enum class QpMethod {
  kNnls,   // Lawson-Hanson NNLS on the dual (default; see README for the measurement)
  kNlopt,  // NLopt SLSQP on the primal QP through the solver adapter
};
QpMethod parse_qp_method(const std::string& name);  // "nnls" | "nlopt"; throws std::invalid_argument
std::string to_string(QpMethod method);

struct Accelerations {
  std::vector<double> a;      // vertical acceleration of each block's centre (0 for fixed blocks)
  std::vector<double> alpha;  // angular acceleration, counter-clockwise positive (0 for fixed blocks)
  std::vector<double> force;  // contact forces: force[2k] at contacts[k].left, force[2k+1] at .right (NNLS only)
  bool converged = true;
  int iterations = 0;
  bool certified = false;  // answered by two_point_certificate() without a QP
  bool moving(size_t i) const;
  bool any_moving() const;
};

// Statics shortcut (O(n)): every free block is assumed to rest on two of its contact ends (first the two
// extreme ends of its support hull; if that fails, for each block the pair that keeps the load nearest the
// middle of the lower blocks' supports), and the forces are computed row by row from the top. If every force is >= -1e-9 x (the load) this is a
// proof that the pile is balanced (all initial accelerations are zero). false means "no proof", not
// "unbalanced". forces (optional): as Accelerations::force.
bool two_point_certificate(const ContactGraph& graph, const std::vector<char>& free = {},
                           std::vector<double>* forces = nullptr);

// free: one flag per block; a block whose flag is 0 is held fixed (it acts like the surface). Empty: all free.
// Throws std::runtime_error when the backend fails.
// certificate: try two_point_certificate() first (off only to measure the QP itself).
// warm_forces (NNLS only, optional): contact forces of a related solution (Accelerations::force, e.g. the same
// pile with more blocks free); the contact ends carrying force there seed the NNLS passive set. Any value
// gives the same answer; a close one saves iterations.
Accelerations initial_accelerations(const ContactGraph& graph, const std::vector<char>& free = {},
                                    QpMethod method = QpMethod::kNnls, bool certificate = true,
                                    const std::vector<double>* warm_forces = nullptr);

}  // namespace bricklayer::core
