// Inverse kinematics of a point on a body of a kinematic tree (multibody/tree.hpp), and optionally
// of the body's orientation, by damped least squares (Wampler 1986; Buss, "Introduction to inverse
// kinematics with Jacobian transpose, pseudoinverse and damped least squares methods", 2004, sec. 5)
// with a Levenberg–Marquardt damping schedule (Nocedal and Wright, Numerical Optimization, 2006,
// sec. 10.3):
//   e   = [p_des - p(q); log(R_des R(q)^T)]       position error (m), then the rotation vector (rad)
//   dq  = J^T (J J^T + lambda² I)^-1 e             J: calc_point_jacobian's rows for e, free dofs only
//         (evaluated as sum_i sigma_i / (sigma_i² + lambda²) v_i u_i^T e over J's SVD),
// each step scaled down to at most 0.5 rad (or m) on any dof and clamped to the joint limits. A step
// that lowers |e| is taken and lambda scaled by max(1/3, 1 - (2 rho - 1)³), rho = the actual over the
// linear model's predicted decrease (Nielsen's 1999 rule, applied to lambda rather than lambda²; Madsen,
// Nielsen and Tingleff, Methods for non-linear least squares problems, 2004, sec. 3.2), floor 1e-9;
// a step that does not is retried with lambda x4. So the solver is Gauss–Newton (quadratic) near a
// solution, gradient descent far from one, and does not oscillate at a large residual (a target
// beyond reach). A dof at a limit whose step points outwards is left out of that step. A stationary
// point (|J^T e| <= 1e-12 sigma_max |e|, or lambda > 1e7 sigma_max) ends the search.
#pragma once

#include <Eigen/Dense>
#include <span>
#include <string>
#include <vector>

#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff {

struct IkTarget {
  int body = 0;                       // the body carrying the point
  Vec3 point = Vec3::Zero();          // in the body frame, m
  Vec3 position = Vec3::Zero();       // desired position of the point in the base frame, m
  bool orient = false;                // also reach `rotation`
  Mat3 rotation = Mat3::Identity();   // desired body orientation in the base frame when orient (active)
  std::string name;                   // in messages when several targets are solved together
};

struct IkOptions {
  // The dofs the solver may move (empty = all); the others keep q0's values bit for bit (e.g. a
  // flexible link's cell joints held at 0, the rigid model).
  std::vector<int> free_dofs;
  double damping = 1e-2;     // initial lambda (m, rad), > 0
  int max_iterations = 200;  // trial steps (each one forward-kinematics evaluation), >= 0
  double tolerance = 1e-9;   // converged when |position error| <= it (m) and |orientation error| <= it (rad)
  bool respect_limits = true;
  std::vector<double> lower, upper;  // per dof (nv entries) or empty = unbounded; rad or m
};

struct IkResult {
  Eigen::VectorXd q;               // the solution, or the best point reached
  bool converged = false;
  double position_error = 0.0;     // |p_des - p(q)|, m (several targets: the largest)
  double orientation_error = 0.0;  // rotation angle of R_des R(q)^T, rad (0 without orient; several: the largest)
  int iterations = 0;              // trial steps taken
  std::string why;                 // why not converged (empty when converged)
};

// Solves from q0. Free dofs start from q0 clamped to their limits (when respect_limits). Failure is
// a result (converged = false, q the best point found, `why`), never an exception:
//   a target outside a ball that holds the point for every q (centred on the chain's root-most
//     moving joint; radius the chain's offsets plus prismatic travels): "target 0.35 m beyond reach
//     (the point stays within 0.9 m of body 0's joint); stationary 0.35 m from it" (with no moving
//     joint on the chain: "target beyond reach: 0.5 m from the point, which no joint moves");
//   a stationary point with dofs at their limits: "target not reached within the joint limits: ...";
//   another stationary point: "stationary 0.19 m, 0.03 rad from the target: a local minimum, or a
//     target the free dofs cannot reach (try another q0)";
//   the iteration limit: "did not converge in 200 iterations; residual 3.1 mm".
// Throws std::invalid_argument on a body out of range, q0 not of nv entries or not finite, a
// non-finite target, a rotation that is not proper orthonormal (when orient), a free dof out of
// range or repeated, limits not of nv entries, NaN (infinities are allowed) or lower > upper, and on
// damping <= 0, max_iterations < 0 or tolerance <= 0.
IkResult solve_inverse_kinematics(const Tree& tree, const Eigen::VectorXd& q0, const IkTarget& target,
                                  const IkOptions& opt = {});

// Several targets at once (e.g. two tool points of a two-armed tree): their tasks stacked, e = [e_1; e_2;
// ...], J = [J_1; J_2; ...] over the same free dofs, solved by the same damped least squares (one
// target: exactly the call above, bit for bit). Converged when every target is within the tolerance;
// a failure's message names the target (IkTarget::name, else its index) it concerns: "right: target
// 0.35 m beyond reach ...", "stationary left 3.1 mm, right 0.19 m from the targets: ...". Throws as
// above for each target, and on an empty list.
IkResult solve_inverse_kinematics(const Tree& tree, const Eigen::VectorXd& q0, std::span<const IkTarget> targets,
                                  const IkOptions& opt = {});

}  // namespace ff
