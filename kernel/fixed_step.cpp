#include "kernel/fixed_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/isa.hpp"
#include "kernel/drive.hpp"
#include "kernel/dynamics.hpp"
#include "kernel/stage_arithmetic.hpp"

namespace ff {

namespace {
// y1 = y + a * k, over all N x W entries.
void axpy(std::size_t n, const double* y, double a, const double* k, double* y1) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) y1[j] = y[j] + a * k[j];
}

// Joint armature gh c + gh^2 k for the implicit spring-damper terms of a stage with coefficient gh
// (row 0: the hub, none); remade only when gh changes.
void set_armature(const BatchModel& bm, Workspace& ws, double gh) {
  if (ws.armature_gh == gh) return;
  for (std::size_t j = static_cast<std::size_t>(bm.W); j < ws.armature.size(); ++j)
    ws.armature[j] = gh * bm.joint_c[j] + gh * gh * bm.joint_k[j];
  ws.armature_gh = gh;
}

// The hub's armature: the friction map and the drive train's transmission linearly implicit, like the
// joint springs and dampers.
// - Friction: gh_f d(tau_f)/dw at the stage's rate w (calc_hub_friction_damping). A steep map (a small
//   smoothing velocity) is then stable at the step the chain needs, not at h < 2 eps J / F. LuGre's
//   bristles are drive states, implicit in solve_drive_stage: no friction term.
// - Transmission (a drive train's shaft without free play): gh c_t + gh^2 k_t, its tangent
//   (calc_transmission_tangent) at the stage's shaft state Z and hub (q, w). The shaft's side is
//   implicit in solve_drive_stage with the hub held; without this the hub's side would be explicit, and
//   the stiff mesh unstable at the automatic step on some chains (the midpoint rule on configs/fbtb.yaml
//   with the drive at N = 12). With free play the mesh's hub side stays explicit: a tangent switching
//   on and off at the gap's edges made diagnose's backlash fits rougher and 1.5 times slower, and did
//   not cure the free play's own divergence at N >= 12 (the session note of 2026-12-04).
void set_hub_armature(const BatchModel& bm, const double* q, const double* w, const double* Z, double gh_f,
                      double gh, Workspace& ws) {
  const DriveLayout& L = bm.layout;
  const int W = bm.W;
  for (int l = 0; l < W; ++l) {
    double a = L.bristle >= 0 ? 0.0 : gh_f * calc_hub_friction_damping(bm, l, q[l], w[l]);
    if (L.shaft >= 0 && bm.drive[l].b == 0.0) {
      const LaneDrive& p = bm.drive[l];
      const TransmissionTangent t =
          calc_transmission_tangent(p, Z[L.shaft * W + l] / p.n - q[l], Z[(L.shaft + 1) * W + l] / p.n - w[l]);
      a += gh * t.damping + gh * gh * t.stiffness;
    }
    ws.armature[l] = a;
  }
}

// The hub drive's part of an SDIRK stage: solves Z = zpre + gh f(q, v, Z) for every lane by
// simplified Newton (Jacobian df/dZ by forward differences at zpre, four iterations), with the
// chain held at (q, v). Writes Z (nz x W); uses ws.zdot and ws.zpert.
void solve_drive_stage(const BatchModel& bm, const double* q, const double* v, const double* tau_cmd,
                       const double* zpre, double gh, double* Z, Workspace& ws) {
  const int W = bm.W, nz = bm.layout.nz;
  const std::size_t nzw = static_cast<std::size_t>(nz) * W;
  constexpr int kMax = 8;  // the most drive states: 4 hydraulic + 2 shaft + 1 bristle
  static const double srur = std::sqrt(std::numeric_limits<double>::epsilon());
  double* f0 = ws.zdot.data();
  double* zp = ws.zpert.data();
  double* fp = ws.znew.data();
  // Iteration matrices I - gh df/dZ of every lane, (nz x nz) each.
  double* jac = ws.zjac.data();
  compute_hub_drive(bm, q, v, zpre, tau_cmd, ws.tau_hub.data(), f0);
  std::copy(zpre, zpre + nzw, zp);
  for (int j = 0; j < nz; ++j) {
    double delta[kMaxLanes];
    for (int l = 0; l < W; ++l) {
      const double zj = zpre[j * W + l];
      delta[l] = (zj + srur * std::max(std::abs(zj), 1.0)) - zj;
      zp[j * W + l] = zj + delta[l];
    }
    compute_hub_drive(bm, q, v, zp, tau_cmd, ws.tau_hub.data(), fp);
    for (int l = 0; l < W; ++l) {
      zp[j * W + l] = zpre[j * W + l];
      for (int i = 0; i < nz; ++i)
        jac[(l * nz + i) * nz + j] = (i == j ? 1.0 : 0.0) - gh * (fp[i * W + l] - f0[i * W + l]) / delta[l];
    }
  }
  std::copy(zpre, zpre + nzw, Z);
  for (int it = 0; it < 4; ++it) {
    compute_hub_drive(bm, q, v, Z, tau_cmd, ws.tau_hub.data(), fp);
    for (int l = 0; l < W; ++l) {
      double A[kMax * kMax], r[kMax];
      std::copy(jac + l * nz * nz, jac + (l + 1) * nz * nz, A);
      for (int i = 0; i < nz; ++i) r[i] = -(Z[i * W + l] - zpre[i * W + l] - gh * fp[i * W + l]);
      solve_small_system(nz, A, r);
      for (int i = 0; i < nz; ++i) Z[i * W + l] += r[i];
    }
  }
}
}  // namespace

static void step_rk4_kernel(const BatchModel& bm, BatchState& s, Workspace& ws, double h) {
  const std::size_t n = s.q.size(), nz = s.z.size();
  double* q = s.q.data();
  double* v = s.v.data();
  double* z = s.z.data();
  double *q1 = ws.q1.data(), *v1 = ws.v1.data(), *z1 = ws.z1.data();
  const double* tau = s.tau.data();
  const BodyTable body = make_body_table(bm, s.tip);
  // Stage derivatives: kq[i] = velocity, kv[i] = acceleration, kz[i] = drive state rate (Butcher tableau of RK4).
  const double c[4] = {0.0, 0.5 * h, 0.5 * h, h};
  for (int st = 0; st < 4; ++st) {
    const double* qs = q;
    const double* vs = v;
    const double* zs = z;
    if (st > 0) {
      axpy(n, q, c[st], ws.kq[st - 1].data(), q1);
      axpy(n, v, c[st], ws.kv[st - 1].data(), v1);
      axpy(nz, z, c[st], ws.kz[st - 1].data(), z1);
      qs = q1;
      vs = v1;
      zs = z1;
    }
    std::copy(vs, vs + n, ws.kq[st].data());
    compute_acceleration(bm, body, qs, vs, zs, tau, ws.kv[st].data(), ws.kz[st].data(), ws);
  }
  rk4_combine(n, ws.kq, ws.kv, h, q, v);
  const double w6 = h / 6.0;
  const double *kz0 = ws.kz[0].data(), *kz1 = ws.kz[1].data(), *kz2 = ws.kz[2].data(), *kz3 = ws.kz[3].data();
  for (std::size_t j = 0; j < nz; ++j) z[j] += w6 * (kz0[j] + 2.0 * kz1[j] + 2.0 * kz2[j] + kz3[j]);
}
FF_ISA_DISPATCH(void, step_rk4, (const BatchModel& bm, BatchState& s, Workspace& ws, double h), (bm, s, ws, h))

static void step_sdirk2_kernel(const BatchModel& bm, BatchState& s, Workspace& ws, double h) {
  const std::size_t n = s.q.size();
  const double g = kSdirk2Gamma;
  const double gh = g * h;
  set_armature(bm, ws, gh);
  const BodyTable body = make_body_table(bm, s.tip);
  double* q = s.q.data();
  double* v = s.v.data();
  double* a_prev = s.a_prev.data();
  double *qs = ws.kq[0].data(), *vs = ws.kv[0].data();        // spring state: Qpre + gh Vpre, Vpre
  double *qk = ws.kq[1].data(), *vk = ws.kv[1].data();        // kinematic predictor of the stage
  double *A1 = ws.kq[2].data(), *A2 = ws.kv[2].data();        // stage accelerations
  sdirk2_stage1(n, q, v, a_prev, gh, qs, vs, qk, vk);
  // The hub drive's stage (implicit, with the chain at the spring state), then its torque on the hub.
  const bool drive = bm.layout.nz > 0;
  double *z = s.z.data(), *Z1 = ws.z1.data(), *Z2 = ws.kz[0].data(), *zpre = ws.kz[1].data();
  if (drive) solve_drive_stage(bm, qs, vs, s.tau.data(), z, gh, Z1, ws);
  compute_hub_drive(bm, qs, vs, Z1, s.tau.data(), ws.tau_hub.data(), nullptr);
  compute_joint_torques(bm, qs, vs, ws.tau_hub.data(), ws.tau_joint.data());
  set_hub_armature(bm, qs, vs, Z1, gh, gh, ws);
  compute_forward_dynamics(bm, body, qk, vk, ws.tau_joint.data(), ws.armature.data(), A1, ws);
  const double b1 = (1.0 - g) * h;
  double* vpre = ws.v1.data();
  double* qpre = ws.q1.data();
  sdirk2_stage2(n, q, v, A1, gh, b1, qpre, vpre, qs, vs, qk, vk);
  // Drive: Z2 = z + (1-g) h F1 + gh f(Z2), with F1 = (Z1 - z) / gh from the first stage.
  if (drive) {
    const std::size_t nz = s.z.size();
    for (std::size_t j = 0; j < nz; ++j) zpre[j] = z[j] + b1 * (Z1[j] - z[j]) / gh;
    solve_drive_stage(bm, qs, vs, s.tau.data(), zpre, gh, Z2, ws);
    std::copy(Z2, Z2 + nz, z);
  }
  compute_hub_drive(bm, qs, vs, z, s.tau.data(), ws.tau_hub.data(), nullptr);
  compute_joint_torques(bm, qs, vs, ws.tau_hub.data(), ws.tau_joint.data());
  set_hub_armature(bm, qs, vs, z, gh, gh, ws);
  compute_forward_dynamics(bm, body, qk, vk, ws.tau_joint.data(), ws.armature.data(), A2, ws);
  sdirk2_finish(n, qpre, vpre, A2, gh, q, v, a_prev);
}
FF_ISA_DISPATCH(void, step_sdirk2, (const BatchModel& bm, BatchState& s, Workspace& ws, double h), (bm, s, ws, h))

static void step_midpoint_kernel(const BatchModel& bm, BatchState& s, Workspace& ws, double h) {
  const std::size_t n = s.q.size();
  const double gh = 0.5 * h;
  set_armature(bm, ws, gh);
  const BodyTable body = make_body_table(bm, s.tip);
  double* q = s.q.data();
  double* v = s.v.data();
  double* a_prev = s.a_prev.data();
  double *qs = ws.kq[0].data(), *vk = ws.kv[0].data(), *A = ws.kv[1].data();
  // Midpoint t + h/2: V = v + (h/2) A, Q = q + (h/2) V = qs + (h/2)^2 A with qs = q + (h/2) v.
  // Springs and dampers at (qs, v) plus the armature; M and velocity terms at (qs, v + (h/2) a_prev).
  midpoint_stage(n, q, v, a_prev, gh, qs, vk);
  // The hub drive by the implicit midpoint rule: Z = z + (h/2) f(Z), z_new = 2 Z - z.
  double* z = s.z.data();
  double* Z = ws.z1.data();
  if (bm.layout.nz > 0) solve_drive_stage(bm, qs, v, s.tau.data(), z, gh, Z, ws);
  compute_hub_drive(bm, qs, v, Z, s.tau.data(), ws.tau_hub.data(), nullptr);
  for (std::size_t j = 0; j < s.z.size(); ++j) z[j] = 2.0 * Z[j] - z[j];
  compute_joint_torques(bm, qs, v, ws.tau_hub.data(), ws.tau_joint.data());
  // The friction map backward-Euler implicit (armature h F', not h/2 F'): the midpoint rule is not
  // L-stable, and a stuck hub would flip its rate's sign every step. The transmission as the springs.
  set_hub_armature(bm, qs, v, Z, h, gh, ws);
  compute_forward_dynamics(bm, body, qs, vk, ws.tau_joint.data(), ws.armature.data(), A, ws);
  midpoint_finish(n, A, h, gh, q, v, a_prev);
}
FF_ISA_DISPATCH(void, step_midpoint, (const BatchModel& bm, BatchState& s, Workspace& ws, double h), (bm, s, ws, h))

}  // namespace ff
