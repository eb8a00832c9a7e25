// Static equilibrium of a kinematic tree (multibody/tree.hpp) with joint springs: the configuration
// q at which gravity, the springs and constant applied generalised forces balance,
//   r(q) = g(q) + K (q - q_ref) - tau_applied = 0,
// g(q) the gravity forces (calc_bias_forces at qd = 0), K = diag(k_i) and q_ref the joints'
// stiffness and spring_reference (the passive forces of calc_passive_forces at qd = 0 are
// -K (q - q_ref)). Point loads become tau_applied by add_point_load (multibody/algorithms.hpp),
// evaluated at one configuration (a small-deflection load; a load that turns with the structure
// needs an outer iteration by the caller).
#pragma once

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "multibody/algorithms.hpp"
#include "multibody/tree.hpp"

namespace ff {

// The static stiffness dr/dq = dg/dq + K at q (nv x nv): dg/dq by central differences of the bias
// forces at qd = 0 with the step fd_step (1 + |q_j|) (rad or m), K exactly. Not symmetric in
// general away from an equilibrium; at q with g = 0 (no gravity) it is exactly K.
void calc_static_stiffness(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, Eigen::Ref<Eigen::MatrixXd> K,
                           TreeWorkspace& ws, double fd_step = 1e-6);

struct StaticEquilibriumOptions {
  int max_iterations = 50;  // Newton iterations
  // Converged when max_i |r_i| <= tolerance * scale, scale = the largest of max|tau_applied|,
  // max|g(q)| and max|K (q - q_ref)| (the forces that balance), N·m or N.
  double tolerance = 1e-10;
  double fd_step = 1e-6;    // the Jacobian's central-difference step (calc_static_stiffness)
  // Dofs held at their q0 value (a joint clamped by its brake or its servo): their residual is the
  // reaction the holding supplies, not balanced.
  std::vector<int> locked_dofs;
};

enum class StaticStatus {
  kConverged,
  kMaxIterations,     // the residual was still above the tolerance
  kSingular,          // dg/dq + K singular: a joint held by neither a spring nor gravity, or buckling
  kLineSearchFailed,  // no step along the Newton direction reduced the residual
  kNotFinite,         // a residual or a step was not finite
};

struct StaticEquilibriumResult {
  StaticStatus status = StaticStatus::kMaxIterations;
  bool converged() const { return status == StaticStatus::kConverged; }
  Eigen::VectorXd q;      // the last iterate (the equilibrium when converged)
  int iterations = 0;     // Newton steps taken
  int jacobians = 0;      // Jacobians evaluated (each 2 nv bias-force evaluations)
  double residual = 0.0;  // max |r(q)|, N·m or N
  double scale = 0.0;     // the force scale the tolerance is relative to
  std::string message;    // what happened, in words
};

// Newton's method on r(q) from q0 (an initial guess; the springs' references are their own
// spring_reference fields), the Jacobian by calc_static_stiffness, kept for the next step (a chord
// step) while full steps shrink max|r| at least 4-fold and evaluated afresh otherwise, and a
// backtracking line search on max|r| (halving the step up to 30 times). Returns a failure status
// and message, never throws, when it does not converge; throws std::invalid_argument only for q0 or
// tau_applied of the wrong size or bad options. Allocates its own workspace.
StaticEquilibriumResult solve_static_equilibrium(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q0,
                                                 const Eigen::Ref<const Eigen::VectorXd>& tau_applied,
                                                 const StaticEquilibriumOptions& options = {});

}  // namespace ff
