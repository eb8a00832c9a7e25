#include "multibody/modes.hpp"

#include "kernel/modes.hpp"  // is_zero_eigenvalue

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "multibody/algorithms.hpp"
#include "multibody/statics.hpp"

namespace ff {

double TreeMode::frequency_hz() const { return omega_n / (2.0 * std::numbers::pi); }

namespace {

// Scales a shape so its largest |entry| is 1 and that entry positive.
void normalise(Eigen::VectorXd& v) {
  Eigen::Index k = 0;
  v.cwiseAbs().maxCoeff(&k);
  if (v[k] != 0.0) v /= v[k];
}

}  // namespace

std::vector<TreeMode> calc_tree_modes(const Tree& tree, const Eigen::Ref<const Eigen::VectorXd>& q0,
                                      const TreeModeOptions& o) {
  const int nv = tree.nv();
  if (q0.size() != nv)
    throw std::invalid_argument("calc_tree_modes: q0 has " + std::to_string(q0.size()) + " entries, the tree " +
                                std::to_string(nv) + " coordinates");
  for (const Eigen::MatrixXd* x : {&o.extra_stiffness, &o.extra_damping})
    if (x->size() != 0 && (x->rows() != nv || x->cols() != nv))
      throw std::invalid_argument("calc_tree_modes: an extra stiffness or damping matrix is not " + std::to_string(nv) +
                                  " x " + std::to_string(nv));
  const int nz = static_cast<int>(o.actuator_z.rows());
  if (o.actuator_z.cols() != nz || o.actuator_force.rows() != (nz ? nv : 0) || o.actuator_force.cols() != nz ||
      o.actuator_q.rows() != nz || o.actuator_q.cols() != (nz ? nv : 0) || o.actuator_qd.rows() != nz ||
      o.actuator_qd.cols() != (nz ? nv : 0))
    throw std::invalid_argument("calc_tree_modes: the actuator matrices are not nv x nz, nz x nv, nz x nv, nz x nz");
  std::vector<char> locked(static_cast<std::size_t>(nv), 0);
  for (int j : o.locked_dofs) {
    if (j < 0 || j >= nv) throw std::invalid_argument("calc_tree_modes: no dof " + std::to_string(j) + " to lock");
    if (locked[static_cast<std::size_t>(j)]) throw std::invalid_argument("calc_tree_modes: dof " + std::to_string(j) + " locked twice");
    locked[static_cast<std::size_t>(j)] = 1;
  }
  std::vector<int> free;
  for (int j = 0; j < nv; ++j)
    if (!locked[static_cast<std::size_t>(j)]) free.push_back(j);
  const int n = static_cast<int>(free.size());
  if (n == 0) return {};

  TreeWorkspace ws(tree);
  Eigen::MatrixXd Mf(nv, nv), Kf(nv, nv), Cf = Eigen::MatrixXd::Zero(nv, nv);
  calc_mass_matrix(tree, q0, Mf, ws);
  calc_static_stiffness(tree, q0, Kf, ws, o.fd_step);
  for (const Body& b : tree.bodies())
    if (b.dof >= 0) Cf(b.dof, b.dof) = b.damping;
  if (o.extra_stiffness.size()) Kf += o.extra_stiffness;
  if (o.extra_damping.size()) Cf += o.extra_damping;
  if (!Mf.allFinite() || !Kf.allFinite()) throw std::invalid_argument("calc_tree_modes: M or K is not finite at q0");
  Eigen::MatrixXd M(n, n), K(n, n), C(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      M(a, b) = Mf(free[a], free[b]);
      K(a, b) = Kf(free[a], free[b]);
      C(a, b) = Cf(free[a], free[b]);
    }
  auto full_shape = [&](const Eigen::VectorXd& x) {
    Eigen::VectorXd s = Eigen::VectorXd::Zero(nv);
    for (int a = 0; a < n; ++a) s[free[a]] = x[a];
    normalise(s);
    return s;
  };

  std::vector<TreeMode> modes;
  if (C.cwiseAbs().maxCoeff() == 0.0 && nz == 0) {
    // K v = w^2 M v with the symmetric part of K.
    const Eigen::MatrixXd Ks = 0.5 * (K + K.transpose());
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(Ks, M);
    if (eig.info() != Eigen::Success) throw std::invalid_argument("calc_tree_modes: M is not positive definite at q0");
    for (int k = 0; k < n; ++k) {
      const double w2 = eig.eigenvalues()[k];
      TreeMode m;
      m.omega_n = std::sqrt(std::abs(w2));
      m.oscillatory = w2 > 0.0;
      m.zeta = w2 > 0.0 ? 0.0 : -1.0;
      m.shape = full_shape(eig.eigenvectors().col(k));
      modes.push_back(m);
    }
  } else {
    // x' = A x, x = [q; qd]: each complex pair once, real poles alone.
    const Eigen::LLT<Eigen::MatrixXd> llt(M);
    if (llt.info() != Eigen::Success) throw std::invalid_argument("calc_tree_modes: M is not positive definite at q0");
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * n + nz, 2 * n + nz);
    A.block(0, n, n, n).setIdentity();
    A.block(n, 0, n, n) = -llt.solve(K);
    A.block(n, n, n, n) = -llt.solve(C);
    if (nz > 0) {
      Eigen::MatrixXd B(n, nz), Zq(nz, n), Zv(nz, n);
      for (int a = 0; a < n; ++a) {
        B.row(a) = o.actuator_force.row(free[a]);
        Zq.col(a) = o.actuator_q.col(free[a]);
        Zv.col(a) = o.actuator_qd.col(free[a]);
      }
      A.block(n, 2 * n, n, nz) = llt.solve(B);
      A.block(2 * n, 0, nz, n) = Zq;
      A.block(2 * n, n, nz, n) = Zv;
      A.block(2 * n, 2 * n, nz, nz) = o.actuator_z;
    }
    const Eigen::EigenSolver<Eigen::MatrixXd> eig(A);
    for (int k = 0; k < 2 * n + nz; ++k) {
      const std::complex<double> lam = eig.eigenvalues()[k];
      if (lam.imag() < 0.0) continue;  // the conjugate of one reported
      TreeMode m;
      m.omega_n = std::abs(lam);
      m.oscillatory = lam.imag() > 0.0;
      m.zeta = m.omega_n > 0.0 ? -lam.real() / m.omega_n : 1.0;
      if (!m.oscillatory) m.zeta = lam.real() <= 0.0 ? 1.0 : -1.0;
      // The q block of the eigenvector, turned so its largest entry is real.
      const Eigen::VectorXcd x = eig.eigenvectors().col(k);
      // Below 1e-6: round-off of a repeated zero eigenvalue in states of mixed units (Pa beside rad)
      // leaves the q block at 1e-9 of the eigenvector (the Titan arm's six actuators).
      m.moves = x.head(2 * n).norm() > 1e-6 * x.norm();
      Eigen::VectorXcd z = x.head(n);
      Eigen::Index big = 0;
      z.cwiseAbs().maxCoeff(&big);
      if (std::abs(z[big]) > 0.0) z *= std::conj(z[big]) / std::abs(z[big]);
      m.shape = full_shape(z.real());
      modes.push_back(m);
    }
  }
  // Round-off of a zero eigenvalue (a free motion) is 0, neither slow nor unstable nor oscillatory.
  const double scale = calc_stiffness_scale(M.llt().solve(K));
  for (TreeMode& m : modes)
    if (is_zero_eigenvalue(m.omega_n, scale)) m.omega_n = 0.0, m.zeta = 1.0, m.oscillatory = false;
  std::stable_sort(modes.begin(), modes.end(), [](const TreeMode& a, const TreeMode& b) { return a.omega_n < b.omega_n; });
  return modes;
}

}  // namespace ff
