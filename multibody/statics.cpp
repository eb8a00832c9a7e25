// Static equilibrium by Newton's method (statics.hpp).
#include "multibody/statics.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace ff {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using ConstVec = Eigen::Ref<const VectorXd>;

std::string sci(double v) {
  std::ostringstream o;
  o.precision(3);
  o << std::scientific << v;
  return o.str();
}

// r = g(q) - passive(q, 0) - tau = g(q) + K (q - q_ref) - tau; also the scale of the balancing forces.
struct Residual {
  VectorXd r, g, spring, zero;
  std::vector<int> locked;  // dofs whose residual is a reaction (set to 0)
  explicit Residual(int n, std::vector<int> held = {}) : r(n), g(n), spring(n), zero(VectorXd::Zero(n)), locked(std::move(held)) {}
  double eval(const Tree& tree, const ConstVec& q, const ConstVec& tau, TreeWorkspace& ws, double* scale) {
    calc_bias_forces(tree, q, zero, g, ws);
    calc_passive_forces(tree, q, zero, spring);
    r = g - spring - tau;
    for (int j : locked) r[j] = 0.0;
    if (scale) {
      *scale = 0.0;
      if (r.size() > 0)
        *scale = std::max({tau.cwiseAbs().maxCoeff(), g.cwiseAbs().maxCoeff(), spring.cwiseAbs().maxCoeff()});
    }
    return r.size() > 0 ? r.cwiseAbs().maxCoeff() : 0.0;
  }
};

}  // namespace

void calc_static_stiffness(const Tree& tree, const ConstVec& q, Eigen::Ref<MatrixXd> K, TreeWorkspace& ws,
                           double fd_step) {
  const int n = tree.nv();
  if (q.size() != tree.nq())
    throw std::invalid_argument("calc_static_stiffness: q has " + std::to_string(q.size()) +
                                " entries, the tree has " + std::to_string(tree.nq()));
  if (K.rows() != n || K.cols() != n)
    throw std::invalid_argument("calc_static_stiffness: K is " + std::to_string(K.rows()) + " x " +
                                std::to_string(K.cols()) + ", the tree has nv = " + std::to_string(n));
  if (!(fd_step > 0.0) || !std::isfinite(fd_step))
    throw std::invalid_argument("calc_static_stiffness: fd_step must be positive and finite");
  const VectorXd zero = VectorXd::Zero(n);
  VectorXd qp = q, gp(n), gm(n);
  // dg/dq_j = (g(q + h e_j) - g(q - h e_j)) / 2h.
  for (int j = 0; j < n; ++j) {
    const double h = fd_step * (1.0 + std::abs(q[j]));
    qp[j] = q[j] + h;
    calc_bias_forces(tree, qp, zero, gp, ws);
    qp[j] = q[j] - h;
    calc_bias_forces(tree, qp, zero, gm, ws);
    qp[j] = q[j];
    K.col(j) = (gp - gm) / (2.0 * h);
  }
  for (const Body& b : tree.bodies())
    if (b.dof >= 0) K(b.dof, b.dof) += b.stiffness;
}

StaticEquilibriumResult solve_static_equilibrium(const Tree& tree, const ConstVec& q0, const ConstVec& tau_applied,
                                                 const StaticEquilibriumOptions& options) {
  const int n = tree.nv();
  if (q0.size() != tree.nq())
    throw std::invalid_argument("solve_static_equilibrium: q0 has " + std::to_string(q0.size()) +
                                " entries, the tree has " + std::to_string(tree.nq()));
  if (tau_applied.size() != n)
    throw std::invalid_argument("solve_static_equilibrium: tau_applied has " + std::to_string(tau_applied.size()) +
                                " entries, the tree has " + std::to_string(n));
  if (options.max_iterations < 0 || !(options.tolerance > 0.0) || !(options.fd_step > 0.0))
    throw std::invalid_argument(
        "solve_static_equilibrium: options need max_iterations >= 0, tolerance > 0 and fd_step > 0");
  for (int j : options.locked_dofs)
    if (j < 0 || j >= n) throw std::invalid_argument("solve_static_equilibrium: locked dof " + std::to_string(j) + " out of range");

  StaticEquilibriumResult res;
  res.q = q0;
  TreeWorkspace ws(tree);
  Residual R(n, options.locked_dofs), trial(n, options.locked_dofs);
  MatrixXd J(n, n);
  auto finish = [&](StaticStatus status, const std::string& what) {
    res.status = status;
    res.message = what + " after " + std::to_string(res.iterations) + " iterations: max |r| = " + sci(res.residual) +
                  " (tolerance " + sci(options.tolerance * res.scale) + ")";
    return res;
  };

  res.residual = R.eval(tree, res.q, tau_applied, ws, &res.scale);
  Eigen::FullPivLU<MatrixXd> lu;
  bool fresh = false;   // lu is the Jacobian at the current iterate
  bool reuse = false;   // the last step contracted fast enough to keep lu (a chord step)
  for (;;) {
    if (!std::isfinite(res.residual)) return finish(StaticStatus::kNotFinite, "the residual is not finite");
    if (res.residual <= options.tolerance * res.scale) return finish(StaticStatus::kConverged, "converged");
    if (res.iterations >= options.max_iterations)
      return finish(StaticStatus::kMaxIterations, "not converged: iteration limit reached");
    if (!reuse) {
      calc_static_stiffness(tree, res.q, J, ws, options.fd_step);
      for (int j : options.locked_dofs) {  // a held dof does not move: its row and column are the identity's
        J.row(j).setZero();
        J.col(j).setZero();
        J(j, j) = 1.0;
      }
      lu.compute(J);
      ++res.jacobians;
      fresh = true;
      if (!lu.isInvertible())
        return finish(StaticStatus::kSingular, "the stiffness dg/dq + K is singular (rank " + std::to_string(lu.rank()) +
                                                   " of " + std::to_string(n) +
                                                   ": a joint held by neither a spring nor gravity, or buckling)");
    }
    const VectorXd step = -lu.solve(R.r);
    if (!step.allFinite()) return finish(StaticStatus::kNotFinite, "the Newton step is not finite");
    // Backtracking: the first of 1, 1/2, 1/4, ... that lowers max |r|.
    bool accepted = false;
    for (int halvings = 0; halvings <= 30 && !accepted; ++halvings) {
      const double alpha = std::ldexp(1.0, -halvings);
      const VectorXd q_try = res.q + alpha * step;
      double scale = 0.0;
      const double r_try = trial.eval(tree, q_try, tau_applied, ws, &scale);
      if (std::isfinite(r_try) && (r_try < res.residual || r_try <= options.tolerance * scale)) {
        // Keep the Jacobian while full steps shrink the residual at least 4-fold.
        reuse = halvings == 0 && r_try <= 0.25 * res.residual;
        res.q = q_try;
        res.residual = r_try;
        res.scale = scale;
        std::swap(R, trial);
        accepted = true;
      }
    }
    if (!accepted) {
      if (!fresh) {  // a stale Jacobian: retry from here with a new one
        reuse = false;
        continue;
      }
      return finish(StaticStatus::kLineSearchFailed, "not converged: the line search found no descent");
    }
    ++res.iterations;
    fresh = false;
  }
}

}  // namespace ff
