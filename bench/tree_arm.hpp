// The trees the MuJoCo benches run on both simulators (bench/tree_mujoco.cpp,
// bench/work_precision.cpp): a case (the variants' TreeSpec, the initial state, a constant applied
// torque), the rigid 6-DOF arm, and one run of fixed steps in flexfarm's tree lanes and in MuJoCo.
#pragma once

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "multibody/algorithms.hpp"
#include "multibody/lane_integrators.hpp"
#include "multibody/lanes.hpp"
#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff::bench {

struct TreeCase {
  std::string name;
  std::function<TreeSpec(double scale)> spec;  // the variant's tree, scale in [0.9, 1.1]
  Eigen::VectorXd q0, qd0, tau;                    // initial state and the constant applied torque
  double ref_h = 1e-6;                             // the reference's RK4 step, s (within its stability limit)
};


// The 6-DOF arm of tests/multibody/mujoco_test.cpp with its trajectory test's joint drive.
inline TreeCase rigid_arm_case() {
  struct Link {
    Vec3 position;
    Mat3 rotation;
    Vec3 axis;
    double mass;
    Vec3 com, principal;
    Mat3 principal_axes;
  };
  const std::vector<Link> links = {
      {{0.0, 0.0, 0.12}, Mat3::Identity(), Vec3::UnitZ(), 4.0, {0.01, -0.02, 0.08}, {0.030, 0.025, 0.020},
       rotz(0.3) * rotx(0.2)},
      {{0.0, 0.06, 0.18}, rotx(0.15), Vec3::UnitY(), 3.2, {0.20, 0.01, 0.02}, {0.010, 0.060, 0.055},
       roty(-0.4) * rotz(0.1)},
      {{0.42, 0.0, 0.03}, rotz(-0.25), Vec3::UnitY(), 2.1, {0.16, -0.015, 0.0}, {0.006, 0.030, 0.028},
       rotx(0.5) * roty(0.2)},
      {{0.36, 0.02, -0.01}, roty(0.3), Vec3::UnitX(), 1.1, {0.05, 0.0, 0.01}, {0.004, 0.003, 0.0035},
       rotz(0.7)},
      {{0.09, 0.0, 0.015}, Mat3::Identity(), Vec3::UnitY(), 0.8, {0.02, 0.01, -0.01}, {0.0015, 0.0012, 0.0010},
       rotx(-0.6) * rotz(0.4)},
      {{0.07, -0.01, 0.0}, rotx(-0.35), Vec3::UnitX(), 0.4, {0.03, 0.0, 0.005}, {0.0004, 0.0006, 0.0005},
       roty(0.9)},
  };
  const double armature[6] = {0.05, 0.08, 0.03, 0.01, 0.005, 0.002};
  const double stiffness[6] = {30.0, 60.0, 40.0, 6.0, 4.0, 1.5};
  const double damping[6] = {0.8, 1.2, 0.6, 0.08, 0.05, 0.01};
  const double q_ref[6] = {0.3, -0.6, 0.9, 0.2, -0.4, 0.5};
  TreeCase c;
  c.name = "rigid 6-DOF arm";
  c.spec = [=](double scale) {
    TreeSpec s;
    for (int i = 0; i < 6; ++i) {
      const Link& l = links[i];
      BodySpec b;
      b.name = "link" + std::to_string(i + 1);
      b.parent = i - 1;
      b.axis = l.axis;
      b.position = l.position;
      b.rotation = l.rotation;
      b.mass = scale * l.mass;
      b.com = l.com;
      b.inertia = scale * l.principal_axes * l.principal.asDiagonal() * l.principal_axes.transpose();
      b.armature = armature[i];
      b.stiffness = stiffness[i];
      b.damping = damping[i];
      b.spring_reference = q_ref[i];
      s.bodies.push_back(b);
    }
    return s;
  };
  const Tree nominal = make_tree(c.spec(1.0));
  TreeWorkspace ws(nominal);
  c.tau.resize(6);
  calc_bias_forces(nominal, Eigen::Map<const Eigen::VectorXd>(q_ref, 6), Eigen::VectorXd::Zero(6), c.tau, ws);
  c.q0.resize(6);
  c.qd0.resize(6);
  c.q0 << 0.7, -0.2, 0.4, 0.9, -1.0, 1.2;
  c.qd0 << 0.5, -0.8, 1.0, -1.5, 2.0, -2.5;
  return c;
}

// Variant v of M: scale 0.9 .. 1.1.
inline double variant_scale(int v, int M) { return M > 1 ? 0.9 + 0.2 * v / (M - 1) : 1.0; }

enum class Method { kFfRk4, kFfSdirk2, kMjEuler, kMjRk4, kMjImplicit, kFfMidpoint };
inline const char* method_name(Method k) {
  switch (k) {
    case Method::kFfRk4: return "flexfarm RK4";
    case Method::kFfSdirk2: return "flexfarm SDIRK2";
    case Method::kMjEuler: return "MuJoCo Euler";
    case Method::kMjRk4: return "MuJoCo RK4";
    case Method::kMjImplicit: return "MuJoCo implicit";
    case Method::kFfMidpoint: return "flexfarm midpoint";
  }
  return "?";
}
inline bool is_flexfarm(Method k) {
  return k == Method::kFfRk4 || k == Method::kFfSdirk2 || k == Method::kFfMidpoint;
}

// flexfarm: `steps` steps of h from the case's initial state in the lanes of tl; q at the end
// (nv x W) into q_end when given. False if a lane left the finite numbers.
inline bool run_flexfarm(const TreeLanes& tl, const double* tau, const TreeCase& c, Method k, double h, long steps,
                  std::vector<double>* q_end, long check_every = 0) {
  const int W = tl.W, nv = tl.nv;
  TreeLanesState s = make_tree_lanes_state(tl);
  TreeStepWorkspace ws(tl);
  for (int j = 0; j < nv; ++j)
    for (int l = 0; l < W; ++l) s.q[j * W + l] = c.q0[j], s.qd[j * W + l] = c.qd0[j];
  auto finite = [&] {
    for (double v : s.q)
      if (!std::isfinite(v) || std::abs(v) > 1e6) return false;
    return true;
  };
  for (long i = 0; i < steps; ++i) {
    if (k == Method::kFfRk4) step_tree_rk4(tl, tau, s, ws, h);
    else if (k == Method::kFfMidpoint) step_tree_midpoint(tl, tau, s, ws, h);
    else step_tree_sdirk2(tl, tau, s, ws, h);
    if (check_every > 0 && i % check_every == 0 && !finite()) return false;  // blown up: stop early
  }
  if (q_end) *q_end = s.q;
  return finite();
}

// MuJoCo: one variant, `steps` steps of mj_step with the model's option as set. False on a
// divergence warning (checked every check_every steps when > 0: then it stops early).
inline bool run_mujoco(const mjModel* m, mjData* d, const TreeCase& c, long steps, long check_every = 0) {
  mj_resetData(m, d);
  const int nv = m->nv;
  for (int j = 0; j < nv; ++j) d->qpos[j] = c.q0[j], d->qvel[j] = c.qd0[j], d->qfrc_applied[j] = c.tau[j];
  auto diverged = [&] {
    for (int w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC})
      if (d->warning[w].number > 0) return true;
    return false;
  };
  for (long i = 0; i < steps; ++i) {
    mj_step(m, d);
    if (check_every > 0 && i % check_every == 0 && diverged()) return false;
  }
  if (diverged()) return false;
  for (int j = 0; j < nv; ++j)
    if (!std::isfinite(d->qpos[j])) return false;
  return true;
}

inline void set_option(mjModel* m, Method k, double h) {
  m->opt.timestep = h;
  m->opt.integrator = k == Method::kMjEuler ? mjINT_EULER : k == Method::kMjRk4 ? mjINT_RK4 : mjINT_IMPLICIT;
}

}  // namespace ff::bench
