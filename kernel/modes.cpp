#include "kernel/modes.hpp"

#include <limits>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernel/drive.hpp"

namespace ff {

double Mode::frequency_hz() const { return omega_n / (2.0 * std::numbers::pi); }

double calc_stiffness_scale(const Eigen::Ref<const Eigen::MatrixXd>& minv_k) {
  return minv_k.size() == 0 ? 0.0 : std::sqrt(minv_k.cwiseAbs().rowwise().sum().maxCoeff());
}

bool is_zero_eigenvalue(double omega, double scale) {
  return omega <= 100.0 * std::sqrt(std::numeric_limits<double>::epsilon()) * scale;
}

Eigen::MatrixXd calc_mass_matrix(const Model& m, const Eigen::VectorXd& q) {
  const int n = m.nseg;
  // Composite inertias, tip to root: IC_parent += X^T IC X (planar spatial inertia, body frames).
  // Scratch kept per thread: the replay calls this at every stage of every step.
  thread_local std::vector<Eigen::Matrix3d> ic, x;
  ic.resize(n);
  x.resize(n);
  for (int i = 0; i < n; ++i) {
    const auto& b = m.body[i];
    ic[i] << b.inertia, 0, b.first, 0, b.mass, 0, b.first, 0, b.mass;
    const double c = std::cos(q[i]), s = std::sin(q[i]), lp = i > 0 ? m.seg_length[i - 1] : 0.0;
    x[i] << 1, 0, 0, s * lp, c, s, c * lp, -s, c;
  }
  for (int i = n - 1; i > 0; --i) ic[i - 1] += x[i].transpose() * ic[i] * x[i];
  // H_ij = S^T X... IC_i S, walking from joint i towards the root.
  Eigen::MatrixXd h(n, n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d f = ic[i].col(0);
    h(i, i) = f[0];
    for (int j = i; j > 0; --j) {
      f = x[j].transpose() * f;
      h(i, j - 1) = h(j - 1, i) = f[0];
    }
  }
  return h;
}

namespace {

// Eigenvalues of a state matrix as modes, ascending in omega_n; complex pairs once.
// `n` coordinates: a's block (n, 0, n, n) is -M^-1 K.
std::vector<Mode> eigen_modes(const Eigen::MatrixXd& a, int n) {
  const Eigen::VectorXcd ev = Eigen::EigenSolver<Eigen::MatrixXd>(a, false).eigenvalues();
  const double scale = calc_stiffness_scale(a.block(n, 0, n, n));
  std::vector<Mode> out;
  for (const auto& l : ev) {
    const double mag = std::abs(l);
    if (l.imag() < 0) continue;
    if (is_zero_eigenvalue(mag, scale)) out.push_back({0.0, 1.0, false});  // free: round-off of zero
    else out.push_back({mag, mag > 0 ? -l.real() / mag : 1.0, l.imag() > 1e-9 * std::max(1.0, mag)});
  }
  std::sort(out.begin(), out.end(), [](const Mode& p, const Mode& q) { return p.omega_n < q.omega_n; });
  return out;
}

// State matrix [[0, I, 0], [-M^-1 K, -M^-1 C, M^-1 b], [r, 0, 0]]; the last row and column only with integral action (ki != 0).
Eigen::MatrixXd state_matrix(const Eigen::MatrixXd& mass, const Eigen::MatrixXd& stiff, const Eigen::MatrixXd& damp,
                             double ki = 0.0) {
  const int n = static_cast<int>(mass.rows());
  const int extra = ki != 0.0 ? 1 : 0;
  const Eigen::LDLT<Eigen::MatrixXd> minv(mass);
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * n + extra, 2 * n + extra);
  a.block(0, n, n, n).setIdentity();
  a.block(n, 0, n, n) = -minv.solve(stiff);
  a.block(n, n, n, n) = -minv.solve(damp);
  if (extra) {
    // Integral action: zdot = -q0 (reference 0), tau += ki z.
    Eigen::VectorXd e0 = Eigen::VectorXd::Zero(n);
    e0[0] = ki;
    a.block(n, 2 * n, n, 1) = minv.solve(e0);
    a(2 * n, 0) = -1.0;
  }
  return a;
}

Eigen::MatrixXd joint_diag(const std::vector<double>& x) {
  return Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size())).asDiagonal();
}

}  // namespace

std::vector<Mode> calc_clamped_modes(const Model& m) {
  const int n = m.nseg - 1;
  if (n == 0) return {};  // a rigid arm: nothing to clamp
  const Eigen::MatrixXd mass = calc_mass_matrix(m, Eigen::VectorXd::Zero(m.nseg));
  return eigen_modes(state_matrix(mass.bottomRightCorner(n, n), joint_diag(m.joint_k).bottomRightCorner(n, n),
                                  joint_diag(m.joint_c).bottomRightCorner(n, n)), n);
}

std::vector<Mode> calc_closed_loop_modes(const Model& m) {
  const int n = m.nseg;
  const auto& c = m.spec.controller;
  Eigen::MatrixXd mass = calc_mass_matrix(m, Eigen::VectorXd::Zero(n));
  Eigen::MatrixXd stiff = joint_diag(m.joint_k), damp = joint_diag(m.joint_c);
  // tau = -kp q0 - kd v0 - g (k1 q1 + c1 v1) + ki z
  stiff(0, 0) += c.kp;
  damp(0, 0) += c.kd;
  if (n > 1) {  // the beam's root moment fed forward; a rigid arm (N = 1) has no joint 1
    stiff(0, 1) += c.load_compensation * m.joint_k[1];
    damp(0, 1) += c.load_compensation * m.joint_c[1];
  }
  // A hydraulic actuator's torque loop, well below its bandwidth, is a torque source in series with
  // a damper: tau = tau_cmd - b_h w, b_h = D^2 p_s / (K K_q) (kernel/drive.hpp).
  const auto& h = m.spec.hydraulics;
  if (h.enabled && h.pressure_gain > 0) damp(0, 0) += calc_hydraulic_damping(h);
  return eigen_modes(state_matrix(mass, stiff, damp, c.ki), n);
}

std::vector<double> calc_resonances(const std::vector<Mode>& closed_loop) {
  std::vector<double> out;
  for (const auto& md : closed_loop)
    if (md.oscillatory && md.zeta < 0.3) out.push_back(md.omega_n);
  return out;
}

std::vector<double> calc_closed_loop_resonances(const Model& m) { return calc_resonances(calc_closed_loop_modes(m)); }

int calc_auto_substeps(const std::vector<Mode>& modes, double control_period, Integrator integrator) {
  double need = 0.0;  // the largest 1/h the modes ask for, 1/s
  for (const auto& md : modes) {
    if (integrator == Integrator::kSdirk2) {
      if (md.oscillatory && md.zeta < 0.3) need = std::max(need, md.omega_n / 0.5);
    } else if (integrator == Integrator::kMidpoint) {
      const bool light = md.oscillatory && md.zeta < 0.3;
      need = std::max(need, light ? md.omega_n / 0.5 : md.omega_n / 4.0);
    } else {
      need = std::max(need, md.oscillatory ? md.omega_n : md.omega_n / 2.5);
    }
  }
  return calc_substeps_for_rate(need, control_period);
}

int calc_substeps_for_rate(double rate, double control_period) {
  const double n = std::ceil(rate * control_period);
  return !(n <= kMaxSubsteps) ? kMaxSubsteps + 1 : std::max(1, static_cast<int>(n));
}

int calc_auto_substeps(const Model& m) {
  auto modes = calc_closed_loop_modes(m);
  const auto clamped = calc_clamped_modes(m);
  modes.insert(modes.end(), clamped.begin(), clamped.end());
  return calc_auto_substeps(modes, m.control_period, m.spec.simulation.integrator);
}

}  // namespace ff
