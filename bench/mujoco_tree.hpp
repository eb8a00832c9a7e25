// A flexfarm tree as MuJoCo sees it, for the benches that run both (bench/tree_mujoco.cpp,
// bench/realtime_arm.cpp): MJCF written from a TreeSpec, compiled from memory, and the check that the
// two are one model (mass matrix and bias forces at a state) before anything is timed.
// (load_mjcf and quiet_warning: bench/mujoco_util.hpp.)
#pragma once

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/mujoco_util.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/tree.hpp"

namespace ff::bench {

inline bool is_identity_placement(const BodySpec& b) {
  return b.position.isZero(0.0) && b.rotation.isIdentity(0.0);
}

// MJCF of the tree: one MuJoCo body per flexfarm body, except that a massless body whose only child
// sits at its origin, unturned, is merged into that child (its joint comes first in the child's
// body: MuJoCo composes a body's joints in order, each about its axis after the ones before).
inline std::string tree_mjcf(const TreeSpec& s) {
  const int nb = static_cast<int>(s.bodies.size());
  std::vector<std::vector<int>> children(static_cast<std::size_t>(nb));
  std::vector<int> roots;
  for (int i = 0; i < nb; ++i) (s.bodies[i].parent < 0 ? roots : children[s.bodies[i].parent]).push_back(i);
  auto merged_into_child = [&](int i) {
    const BodySpec& b = s.bodies[i];
    return b.mass == 0.0 && b.inertia.isZero(0.0) && children[i].size() == 1 &&
           is_identity_placement(s.bodies[children[i][0]]);
  };
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"tree\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"" << s.gravity.x() << ' ' << s.gravity.y() << ' ' << s.gravity.z()
    << "\" timestep=\"0.001\" integrator=\"Euler\">\n"
    << "    <flag contact=\"disable\"/>\n  </option>\n"
    << "  <default><joint armature=\"0\" damping=\"0\" frictionloss=\"0\" stiffness=\"0\" limited=\"false\"/></default>\n"
    << "  <worldbody>\n";
  std::function<void(int, std::string)> emit = [&](int i, std::string indent) {
    const BodySpec& first = s.bodies[i];
    const Eigen::Quaterniond q(first.rotation);
    x << indent << "<body name=\"" << (first.name.empty() ? "b" + std::to_string(i) : first.name) << "\" pos=\""
      << first.position.x() << ' ' << first.position.y() << ' ' << first.position.z() << "\" quat=\"" << q.w() << ' '
      << q.x() << ' ' << q.y() << ' ' << q.z() << "\">\n";
    const std::string in = indent + "  ";
    int cur = i;
    for (;;) {
      const BodySpec& b = s.bodies[cur];
      if (b.joint != JointType::kFixed) {
        const Vec3 a = b.axis.normalized();
        x << in << "<joint name=\"j" << cur << "\" type=\"" << (b.joint == JointType::kRevolute ? "hinge" : "slide")
          << "\" pos=\"0 0 0\" axis=\"" << a.x() << ' ' << a.y() << ' ' << a.z() << "\" armature=\"" << b.armature
          << "\" stiffness=\"" << b.stiffness << "\" springref=\"" << b.spring_reference << "\" damping=\""
          << b.damping << "\"/>\n";
      }
      if (!merged_into_child(cur)) break;
      cur = children[cur][0];
    }
    const BodySpec& b = s.bodies[cur];
    if (b.mass > 0.0) {
      // Principal moments and axes; a diagonal tensor is written as it is.
      Vec3 d;
      Eigen::Quaterniond iq = Eigen::Quaterniond::Identity();
      const Mat3 I = 0.5 * (b.inertia + b.inertia.transpose());
      if ((I - Mat3(I.diagonal().asDiagonal())).isZero(0.0)) {
        d = I.diagonal();
      } else {
        Eigen::SelfAdjointEigenSolver<Mat3> es(I);
        Mat3 R = es.eigenvectors();
        if (R.determinant() < 0) R.col(2) *= -1.0;
        d = es.eigenvalues();
        iq = Eigen::Quaterniond(R);
      }
      x << in << "<inertial pos=\"" << b.com.x() << ' ' << b.com.y() << ' ' << b.com.z() << "\" mass=\"" << b.mass
        << "\" quat=\"" << iq.w() << ' ' << iq.x() << ' ' << iq.y() << ' ' << iq.z() << "\" diaginertia=\"" << d.x()
        << ' ' << d.y() << ' ' << d.z() << "\"/>\n";
    }
    for (int c : children[cur]) emit(c, in);
    x << indent << "</body>\n";
  };
  for (int r : roots) emit(r, "    ");
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

// The MuJoCo model is the flexfarm tree: M(q) and the bias forces (with the joint springs and
// dampers, qfrc_bias - qfrc_passive) at a state; the max relative differences.
inline void check_models(const mjModel* m, const Tree& tree, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                  double& dM, double& dbias) {
  const int nv = tree.nv();
  if (m->nv != nv || m->nq != nv) throw std::runtime_error("MuJoCo model has another number of dofs");
  mjData* d = mj_makeData(m);
  for (int j = 0; j < nv; ++j) d->qpos[j] = q[j], d->qvel[j] = qd[j];
  mj_forward(m, d);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> full(nv, nv);
  mj_fullM(m, full.data(), d->qM);
  TreeWorkspace ws(tree);
  Eigen::MatrixXd M(nv, nv);
  Eigen::VectorXd bias(nv), passive(nv);
  calc_mass_matrix(tree, q, M, ws);
  calc_bias_forces(tree, q, qd, bias, ws);
  calc_passive_forces(tree, q, qd, passive);
  Eigen::VectorXd mj_bias(nv);
  for (int j = 0; j < nv; ++j) mj_bias[j] = d->qfrc_bias[j] - d->qfrc_passive[j];
  dM = (M - full).cwiseAbs().maxCoeff() / M.cwiseAbs().maxCoeff();
  dbias = (bias - passive - mj_bias).cwiseAbs().maxCoeff() / std::max(1e-300, (bias - passive).cwiseAbs().maxCoeff());
  mj_deleteData(d);
}

}  // namespace ff::bench
