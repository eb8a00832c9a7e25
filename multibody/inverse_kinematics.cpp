// Damped-least-squares inverse kinematics (inverse_kinematics.hpp).
// GCC 12 warns of a maybe-uninitialized value inside Eigen's Householder products (JacobiSVD's QR
// preconditioner), a false positive of its inliner; silenced for this file only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "multibody/inverse_kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

#include "multibody/algorithms.hpp"

namespace ff {

namespace {

constexpr double kMaxStep = 0.5;     // largest change of any dof in one step, rad or m
constexpr double kLambdaMin = 1e-9;  // m, rad: lambda's floor (Gauss–Newton below it)
constexpr double kGrow = 4.0;        // lambda after a step that does not lower |e|
// A stationary point: |J^T e| below this times sigma_max |e| (the error at 1e-12 rad to J's
// range), or lambda beyond kLambdaStall sigma_max (a step of ~1e-14 |e| that still fails).
constexpr double kStationary = 1e-12;
constexpr double kLambdaStall = 1e7;
constexpr double kSingular = 1e-12;  // singular values below this times the largest are zero

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("solve_inverse_kinematics: " + what);
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// "0.35 m" at 0.1 m and above, "3.1 mm" below.
std::string length(double m) { return m >= 0.1 ? fmt("%.3g m", m) : fmt("%.3g mm", 1e3 * m); }

using Vec6 = Eigen::Matrix<double, 6, 1>;

// e = [p_des - p(q); log(R_des R(q)^T)] (the second part only when orient).
Vec6 residual(const Tree& tree, const Eigen::VectorXd& q, const IkTarget& target) {
  const Pose pose = calc_body_pose(tree, q, target.body);
  Vec6 e = Vec6::Zero();
  e.head<3>() = target.position - pose.point(target.point);
  if (target.orient) {
    const Eigen::AngleAxisd aa(Mat3(target.rotation * pose.rotation.transpose()));
    e.tail<3>() = aa.angle() * aa.axis();
  }
  return e;
}

void check_arguments(const Tree& tree, const Eigen::VectorXd& q0, const IkTarget& target, const IkOptions& opt) {
  const int nv = tree.nv();
  if (target.body < 0 || target.body >= tree.num_bodies())
    fail("no body " + std::to_string(target.body) + " (the tree has " + std::to_string(tree.num_bodies()) + ")");
  if (q0.size() != nv)
    fail("q0 has " + std::to_string(q0.size()) + " entries, the tree has nv = " + std::to_string(nv));
  if (!q0.allFinite()) fail("q0 is not finite");
  if (!target.point.allFinite() || !target.position.allFinite()) fail("the target point or position is not finite");
  if (target.orient) {
    const Mat3& R = target.rotation;
    if (!R.allFinite() || (R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff() > 1e-9 || R.determinant() <= 0.0)
      fail("the target rotation is not a proper rotation matrix (R^T R = I, det R = +1 to 1e-9)");
  }
  std::vector<bool> seen(static_cast<std::size_t>(nv), false);
  for (int d : opt.free_dofs) {
    if (d < 0 || d >= nv) fail("free dof " + std::to_string(d) + " is out of range (nv = " + std::to_string(nv) + ")");
    if (seen[static_cast<std::size_t>(d)]) fail("free dof " + std::to_string(d) + " is listed twice");
    seen[static_cast<std::size_t>(d)] = true;
  }
  for (const auto* lim : {&opt.lower, &opt.upper}) {
    const char* which = lim == &opt.lower ? "lower" : "upper";
    if (!lim->empty() && static_cast<int>(lim->size()) != nv)
      fail(std::string(which) + " limits have " + std::to_string(lim->size()) + " entries, the tree has nv = " +
           std::to_string(nv));
    for (std::size_t j = 0; j < lim->size(); ++j)
      if (std::isnan((*lim)[j])) fail(std::string(which) + " limit of dof " + std::to_string(j) + " is NaN");
  }
  if (!opt.lower.empty() && !opt.upper.empty())
    for (int j = 0; j < nv; ++j)
      if (opt.lower[j] > opt.upper[j])
        fail("dof " + std::to_string(j) + ": lower limit " + fmt("%g", opt.lower[j]) + " is above the upper " +
             fmt("%g", opt.upper[j]));
  if (!(opt.damping > 0.0) || !std::isfinite(opt.damping)) fail("damping must be positive and finite");
  if (opt.max_iterations < 0) fail("max_iterations must be >= 0");
  if (!(opt.tolerance > 0.0)) fail("tolerance must be positive");
}

// An upper bound on the point's reach: the centre (base frame) and radius (m, infinite when a prismatic
// joint's travel is unbounded) of a ball holding the point for every q. Centre: the joint frame origin
// of the chain's root-most moving joint (fixed, its ancestors being fixed joints); radius: the chain's
// joint frame offsets below it, the point's offset and each prismatic joint's largest travel (a free
// dof's max(|lower|, |upper|), another's |q0|), since revolute joints turn lengths without changing them.
struct Reach {
  Vec3 centre;
  double radius;
  int root;  // the root-most moving body, -1 if none
};
Reach reach_bound(const Tree& tree, const Eigen::VectorXd& q0, const IkTarget& target, const std::vector<bool>& is_free,
                  const Eigen::VectorXd& lo, const Eigen::VectorXd& hi) {
  int root = -1;
  for (int j = target.body; j >= 0; j = tree.body(j).parent)
    if (tree.body(j).dof >= 0) root = j;
  if (root < 0) return {calc_point_position(tree, q0, target.body, target.point), 0.0, -1};
  double radius = target.point.norm();
  for (int j = target.body;; j = tree.body(j).parent) {
    const Body& b = tree.body(j);
    if (b.joint == JointType::kPrismatic)
      radius += is_free[static_cast<std::size_t>(b.dof)] ? std::max(std::abs(lo[b.dof]), std::abs(hi[b.dof]))
                                                        : std::abs(q0[b.dof]);
    if (j == root) break;
    radius += b.X_tree.position().norm();
  }
  const Body& r = tree.body(root);
  const Vec3 centre = r.parent < 0 ? r.X_tree.position() : calc_body_pose(tree, q0, r.parent).point(r.X_tree.position());
  return {centre, radius, root};
}

}  // namespace

IkResult solve_inverse_kinematics(const Tree& tree, const Eigen::VectorXd& q0, const IkTarget& target,
                                  const IkOptions& opt) {
  return solve_inverse_kinematics(tree, q0, std::span<const IkTarget>(&target, 1), opt);
}

IkResult solve_inverse_kinematics(const Tree& tree, const Eigen::VectorXd& q0, std::span<const IkTarget> targets,
                                  const IkOptions& opt) {
  if (targets.empty()) fail("no target");
  for (const IkTarget& target : targets) check_arguments(tree, q0, target, opt);
  const int nv = tree.nv();
  const std::size_t nt = targets.size();
  // The stacked task: target k's rows from row0[k] (3, or 6 with orient).
  std::vector<int> row0(nt), rows_of(nt);
  int rows = 0;
  for (std::size_t k = 0; k < nt; ++k) {
    rows_of[k] = targets[k].orient ? 6 : 3;
    row0[k] = rows;
    rows += rows_of[k];
  }
  const auto label = [&](std::size_t k) {
    return targets[k].name.empty() ? "target " + std::to_string(k) : targets[k].name;
  };

  std::vector<int> moving = opt.free_dofs;
  if (moving.empty())
    for (int j = 0; j < nv; ++j) moving.push_back(j);
  const int m = static_cast<int>(moving.size());
  constexpr double inf = std::numeric_limits<double>::infinity();
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(nv, -inf), hi = Eigen::VectorXd::Constant(nv, inf);
  if (opt.respect_limits) {
    if (!opt.lower.empty()) lo = Eigen::Map<const Eigen::VectorXd>(opt.lower.data(), nv);
    if (!opt.upper.empty()) hi = Eigen::Map<const Eigen::VectorXd>(opt.upper.data(), nv);
  }

  IkResult r;
  r.q = q0;
  for (int d : moving) r.q[d] = std::clamp(r.q[d], lo[d], hi[d]);
  // Each target's residual and the task's cost sum |e_k|² (one target: e.squaredNorm() exactly).
  std::vector<Vec6> e(nt), e_trial(nt);
  const auto evaluate = [&](const Eigen::VectorXd& q, std::vector<Vec6>& out) {
    double c = 0.0;
    for (std::size_t k = 0; k < nt; ++k) {
      out[k] = residual(tree, q, targets[k]);
      c += out[k].squaredNorm();
    }
    return c;
  };
  double cost = evaluate(r.q, e);
  const auto worst = [&](int part) {
    double w = 0.0;
    for (const Vec6& ek : e) w = std::max(w, part == 0 ? ek.head<3>().norm() : ek.tail<3>().norm());
    return w;
  };
  auto finish = [&](bool converged, std::string why) {
    r.converged = converged;
    r.position_error = worst(0);
    r.orientation_error = worst(1);
    r.why = std::move(why);
    return r;
  };
  auto residual_of = [&](std::size_t k) {
    std::string s = length(e[k].head<3>().norm());
    if (targets[k].orient) s += ", " + fmt("%.3g rad", e[k].tail<3>().norm());
    return s;
  };
  auto residual_text = [&]() {
    if (nt == 1) return residual_of(0);
    std::string s;
    for (std::size_t k = 0; k < nt; ++k) s += (k ? ", " : "") + label(k) + " " + residual_of(k);
    return s;
  };

  TreeWorkspace ws(tree);
  Eigen::MatrixXd J6(6, nv), J(rows, m), Jm(rows, m);
  Eigen::VectorXd dq(m), q_trial(nv), er(rows);
  std::vector<bool> locked(static_cast<std::size_t>(m));
  double lambda = opt.damping;

  for (;;) {
    if (worst(0) <= opt.tolerance && worst(1) <= opt.tolerance) return finish(true, "");
    if (r.iterations >= opt.max_iterations)
      return finish(false, "did not converge in " + std::to_string(opt.max_iterations) + " iterations; residual " +
                               residual_text());
    // J's rows for e: calc_point_jacobian gives [omega; v], e is [position; orientation].
    for (std::size_t k = 0; k < nt; ++k) {
      const IkTarget& target = targets[k];
      calc_point_jacobian(tree, r.q, target.body, target.point, J6, ws);
      for (int c = 0; c < m; ++c) {
        J.block<3, 1>(row0[k], c) = J6.block<3, 1>(3, moving[c]);
        if (target.orient) J.block<3, 1>(row0[k] + 3, c) = J6.block<3, 1>(0, moving[c]);
      }
      er.segment(row0[k], rows_of[k]) = e[k].head(rows_of[k]);
    }
    // Trial steps at growing lambda until one lowers |e|.
    bool stalled = false;
    std::vector<int> at_limit;
    for (;;) {
      // dq = sum sigma_i / (sigma_i² + lambda²) v_i u_i^T e, with the dofs at a limit whose step points
      // outwards taken out (their columns zeroed, so their dq is 0) until no more are found.
      std::fill(locked.begin(), locked.end(), false);
      Jm = J;
      double sigma_max = 0.0;
      for (int pass = 0; pass <= m && m > 0; ++pass) {  // (no SVD of an empty J)
        const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jm, Eigen::ComputeThinU | Eigen::ComputeThinV);
        const Eigen::VectorXd& sv = svd.singularValues();
        sigma_max = sv.size() > 0 ? sv[0] : 0.0;
        dq.setZero();
        for (Eigen::Index i = 0; i < sv.size(); ++i) {
          if (!(sv[i] > kSingular * sigma_max)) break;
          dq += (sv[i] / (sv[i] * sv[i] + lambda * lambda) * svd.matrixU().col(i).dot(er)) * svd.matrixV().col(i);
        }
        bool more = false;
        for (int c = 0; c < m; ++c) {
          const double qc = r.q[moving[c]];
          if (!locked[c] && ((qc <= lo[moving[c]] && dq[c] < 0.0) || (qc >= hi[moving[c]] && dq[c] > 0.0))) {
            locked[c] = true;
            Jm.col(c).setZero();
            more = true;
          }
        }
        if (!more) break;
      }
      at_limit.clear();
      for (int c = 0; c < m; ++c)
        if (locked[c]) at_limit.push_back(moving[c]);
      const double biggest = dq.size() > 0 ? dq.cwiseAbs().maxCoeff() : 0.0;
      const double gradient = (Jm.transpose() * er).norm();
      if (biggest == 0.0 || gradient <= kStationary * sigma_max * er.norm() || lambda > kLambdaStall * sigma_max) {
        stalled = true;
        break;
      }
      if (biggest > kMaxStep) dq *= kMaxStep / biggest;
      q_trial = r.q;
      for (int c = 0; c < m; ++c) q_trial[moving[c]] = std::clamp(r.q[moving[c]] + dq[c], lo[moving[c]], hi[moving[c]]);
      const double cost_trial = evaluate(q_trial, e_trial);
      ++r.iterations;
      if (cost_trial < cost) {
        // The gain ratio rho = actual / predicted (by e - J dq) decrease sets lambda (Nielsen 1999:
        // x max(1/3, 1 - (2 rho - 1)³)): a step the linear model overrates (large residuals, where
        // Gauss–Newton overshoots and oscillates) raises it, a faithful one lowers it.
        for (int c = 0; c < m; ++c) dq[c] = q_trial[moving[c]] - r.q[moving[c]];
        const double predicted = cost - (er - J * dq).squaredNorm();
        const double rho = predicted > 0.0 ? (cost - cost_trial) / predicted : 0.0;
        lambda = std::max(lambda * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)), kLambdaMin);
        r.q = q_trial;
        e.swap(e_trial);
        cost = cost_trial;
        break;
      }
      lambda *= kGrow;
      if (r.iterations >= opt.max_iterations) break;
    }
    if (stalled) {
      std::vector<bool> is_free(static_cast<std::size_t>(nv), false);
      for (int d : moving) is_free[static_cast<std::size_t>(d)] = true;
      for (std::size_t k = 0; k < nt; ++k) {
        const IkTarget& target = targets[k];
        const Reach reach = reach_bound(tree, q0, target, is_free, lo, hi);
        const double beyond = (target.position - reach.centre).norm() - reach.radius;
        if (!(beyond > 0.0 && e[k].head<3>().norm() > opt.tolerance)) continue;
        const std::string who = nt == 1 ? "" : label(k) + ": ";
        if (reach.root < 0)
          return finish(false, who + "target beyond reach: " + length(beyond) + " from the point, which no joint moves");
        return finish(false, who + "target " + length(beyond) + " beyond reach (the point stays within " +
                                 length(reach.radius) + " of body " + std::to_string(reach.root) +
                                 "'s joint); stationary " + residual_of(k) + " from it");
      }
      const char* from = nt == 1 ? " from it" : " from the targets";
      if (!at_limit.empty()) {
        std::string dofs;
        for (int d : at_limit) dofs += (dofs.empty() ? "" : ", ") + std::to_string(d);
        return finish(false, "target" + std::string(nt == 1 ? "" : "s") + " not reached within the joint limits: stationary " +
                                 residual_text() + from + " with dof" + (at_limit.size() > 1 ? "s " : " ") + dofs +
                                 " at a limit");
      }
      return finish(false, "stationary " + residual_text() +
                               (nt == 1 ? " from the target" : " from the targets") +
                               ": a local minimum, or a target the free dofs cannot reach "
                               "(try another q0)");
    }
  }
}

}  // namespace ff

#pragma GCC diagnostic pop
