// The reference rig (docs/reference-rig.md) as MuJoCo sees it, for the benches that run both
// (bench/mujoco_compare.cpp, bench/work_precision.cpp): the rig's ModelSpec with the reference
// motion, its MJCF, the checks that MuJoCo kept the model as written, one variant's run in MuJoCo
// with flexfarm's PD and zero-order hold, and the tip-deflection error of a trace.
#pragma once

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernel/model.hpp"
#include "kernel/modes.hpp"
#include "kernel/trajectory.hpp"

namespace ff::bench {

// The reference motion: 0 -> 0.5 rad in 3 s, held 17 s (20 s, 20000 controller steps);
// seconds < 20 simulates only the start of it.
inline ModelSpec rig_spec(int nseg, Integrator integrator, int substeps, double seconds) {
  ModelSpec s;
  s.simulation.duration = seconds;
  s.segments = nseg;
  s.trajectory.moves = {{0.5, 17.0}};
  s.simulation.integrator = integrator;
  s.simulation.substeps = substeps;
  return s;
}

// ---------------------------------------------------------------- MuJoCo model

// Box inertia about the segment centre: x along the beam, z vertical. Izz is flexfarm's seg_inertia;
// Ixx, Iyy are never excited (all hinges about z) but satisfy the triangle inequality.
struct Diag {
  double x, y, z;
};

// MJCF of the rig: nested bodies, one hinge about z per segment, payload body welded at the tip.
inline std::string rig_mjcf(const Model& m, const char* integrator, int substeps) {
  const auto& b = m.spec.beam;
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"fbtb\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"0 0 0\" timestep=\"" << m.control_period / substeps << "\" integrator=\"" << integrator << "\">\n"
    << "    <flag contact=\"disable\"/>\n  </option>\n  <worldbody>\n";
  std::string indent = "    ";
  for (int i = 0; i < m.nseg; ++i) {
    const double li = m.seg_length[i], mi = m.seg_mass[i];
    const Diag in{mi * (b.height * b.height + b.thickness * b.thickness) / 12.0,
                  mi * (li * li + b.height * b.height) / 12.0, m.seg_inertia[i]};
    x << indent << "<body name=\"seg" << i << "\" pos=\"" << (i == 0 ? 0.0 : m.seg_length[i - 1]) << " 0 0\">\n";
    indent += "  ";
    // Hub joint: the hub inertia is its armature (a rotor inertia on the dof). Others: spring + damper.
    x << indent << "<joint name=\"j" << i << "\" type=\"hinge\" axis=\"0 0 1\" pos=\"0 0 0\" limited=\"false\"";
    if (i == 0)
      x << " armature=\"" << m.spec.hub_inertia << "\"";
    else
      x << " stiffness=\"" << m.joint_k[i] << "\" damping=\"" << m.joint_c[i] << "\" springref=\"0\"";
    x << "/>\n";
    x << indent << "<inertial pos=\"" << 0.5 * li << " 0 0\" mass=\"" << mi << "\" diaginertia=\"" << in.x << " "
      << in.y << " " << in.z << "\"/>\n";
  }
  const double ip = m.spec.payload_inertia;
  x << indent << "<body name=\"payload\" pos=\"" << m.seg_length.back() << " 0 0\">\n"
    << indent << "  <inertial pos=\"0 0 0\" mass=\"" << m.spec.payload_mass << "\" diaginertia=\"" << ip << " " << ip
    << " " << ip << "\"/>\n"
    << indent << "</body>\n";
  for (int i = m.nseg - 1; i >= 0; --i) {
    indent.resize(indent.size() - 2);
    x << indent << "</body>\n";
  }
  x << "  </worldbody>\n  <actuator>\n"
    << "    <motor name=\"hub\" joint=\"j0\" gear=\"1\" ctrllimited=\"false\"/>\n  </actuator>\n</mujoco>\n";
  return x.str();
}

// MuJoCo's compiled body inertias must be the ones written (no rebalancing, no axis reordering).
inline bool mujoco_inertia_as_written(const mjModel* mm, const Model& m) {
  const auto& b = m.spec.beam;
  bool ok = true;
  for (int i = 0; i < m.nseg; ++i) {
    const int id = i + 1;  // body 0 is the world
    const double li = m.seg_length[i], mi = m.seg_mass[i];
    const double want[3] = {mi * (b.height * b.height + b.thickness * b.thickness) / 12.0,
                            mi * (li * li + b.height * b.height) / 12.0, m.seg_inertia[i]};
    for (int a = 0; a < 3; ++a) ok &= std::abs(mm->body_inertia[3 * id + a] - want[a]) <= 1e-12 * want[a];
    ok &= mm->body_iquat[4 * id] == 1.0 && std::abs(mm->body_mass[id] - mi) <= 1e-12 * mi;
  }
  return ok;
}

// Max relative difference of MuJoCo's joint-space mass matrix at q = 0 from flexfarm's.
inline double mass_matrix_difference(const mjModel* mm, const Model& m) {
  mjData* d = mj_makeData(mm);
  mj_forward(mm, d);
  const int n = mm->nv;
  std::vector<mjtNum> full(static_cast<std::size_t>(n) * n);
  mj_fullM(mm, full.data(), d->qM);
  mj_deleteData(d);
  const Eigen::MatrixXd ref = calc_mass_matrix(m, Eigen::VectorXd::Zero(m.nseg));
  const double scale = ref.cwiseAbs().maxCoeff();
  double worst = 0.0;
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      worst = std::max(worst, std::abs(full[r * n + c] - ref(r, c)) / std::max(std::abs(ref(r, c)), 1e-12 * scale));
  return worst;
}

// Tip deflection sum L_i sin(q_1 + ... + q_i) from MuJoCo's relative hinge angles.
inline double mujoco_tip(const double* qpos, const Model& m) {
  double phi = 0.0, defl = 0.0;
  for (int i = 0; i < m.nseg; ++i) {
    if (i > 0) phi += qpos[i];
    defl += m.seg_length[i] * std::sin(phi);
  }
  return defl;
}

inline bool mujoco_diverged(const mjData* d) {
  for (int w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC, mjWARN_BADCTRL})
    if (d->warning[w].number > 0) return true;
  return false;
}

// One variant from rest: PD sampled at t_k = k T from the state at t_k, held over the substeps of the
// period. tip (nsamples) receives the tip deflection at every sample, as flexfarm's traces do.
// Returns false (early) when MuJoCo diverged.
inline bool run_rig_mujoco(const mjModel* mm, mjData* d, const Model& m, int substeps, long nsamples, double* tip) {
  mj_resetData(mm, d);
  const double T = m.control_period, kp = m.spec.controller.kp, kd = m.spec.controller.kd;
  for (long k = 0; k < nsamples; ++k) {
    const double r = calc_reference(m.spec.trajectory, k * T);
    d->ctrl[0] = kp * (r - d->qpos[0]) - kd * d->qvel[0];
    tip[k] = mujoco_tip(d->qpos, m);
    if (k + 1 == nsamples) break;
    for (int j = 0; j < substeps; ++j) mj_step(mm, d);
    if (mujoco_diverged(d)) return false;
  }
  return true;
}

struct TipError {
  double rms, max;
};
inline TipError compare_tips(const std::vector<double>& a, const std::vector<double>& ref) {
  if (a.size() != ref.size()) throw std::runtime_error("trace lengths differ");
  double ss = 0.0, mx = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const double e = a[k] - ref[k];
    ss += e * e;
    mx = std::max(mx, std::abs(e));
  }
  return {std::sqrt(ss / a.size()), mx};
}

inline double rms(const std::vector<double>& a) {
  double ss = 0.0;
  for (double x : a) ss += x * x;
  return std::sqrt(ss / a.size());
}

}  // namespace ff::bench
