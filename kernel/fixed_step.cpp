#include "kernel/fixed_step.hpp"

#include "kernel/dynamics.hpp"

namespace ff {

namespace {
// y1 = y + a * k, over all N x W entries.
void axpy(std::size_t n, const double* y, double a, const double* k, double* y1) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) y1[j] = y[j] + a * k[j];
}
}  // namespace

void step_rk4(const BatchModel& bm, BatchState& s, Workspace& ws, double h) {
  const std::size_t n = s.q.size();
  double* q = s.q.data();
  double* v = s.v.data();
  double *q1 = ws.q1.data(), *v1 = ws.v1.data();
  const double* tau = s.tau.data();
  // Stage derivatives: kq[i] = velocity, kv[i] = acceleration (Butcher tableau of RK4).
  const double c[4] = {0.0, 0.5 * h, 0.5 * h, h};
  for (int st = 0; st < 4; ++st) {
    const double* qs = q;
    const double* vs = v;
    if (st > 0) {
      axpy(n, q, c[st], ws.kq[st - 1].data(), q1);
      axpy(n, v, c[st], ws.kv[st - 1].data(), v1);
      qs = q1;
      vs = v1;
    }
    std::copy(vs, vs + n, ws.kq[st].data());
    compute_acceleration(bm, qs, vs, tau, ws.kv[st].data(), ws);
  }
  // y += h/6 (k1 + 2 k2 + 2 k3 + k4)
  const double w6 = h / 6.0;
  const double *kq0 = ws.kq[0].data(), *kq1 = ws.kq[1].data(), *kq2 = ws.kq[2].data(), *kq3 = ws.kq[3].data();
  const double *kv0 = ws.kv[0].data(), *kv1 = ws.kv[1].data(), *kv2 = ws.kv[2].data(), *kv3 = ws.kv[3].data();
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    q[j] += w6 * (kq0[j] + 2.0 * kq1[j] + 2.0 * kq2[j] + kq3[j]);
    v[j] += w6 * (kv0[j] + 2.0 * kv1[j] + 2.0 * kv2[j] + kv3[j]);
  }
}

void step_sdirk2(const BatchModel& bm, BatchState& s, Workspace& ws, double h) {
  const std::size_t n = s.q.size();
  const int W = bm.W;
  const double g = 1.0 - 0.70710678118654752440;  // gamma
  const double gh = g * h;
  // Joint armature h gamma c + (h gamma)^2 k: the implicit spring-damper terms (row 0: the hub, none).
  if (ws.armature_gh != gh) {
    for (std::size_t j = static_cast<std::size_t>(W); j < n; ++j)
      ws.armature[j] = gh * bm.joint_c[j] + gh * gh * bm.joint_k[j];
    ws.armature_gh = gh;
  }
  double* q = s.q.data();
  double* v = s.v.data();
  double* a_prev = ws.a_prev.data();
  double *qs = ws.kq[0].data(), *vs = ws.kv[0].data();        // spring state: Qpre + gh Vpre, Vpre
  double *qk = ws.kq[1].data(), *vk = ws.kv[1].data();        // kinematic predictor of the stage
  double *A1 = ws.kq[2].data(), *A2 = ws.kv[2].data();        // stage accelerations
  // Stage 1 (t + gamma h): Q1 = q + gh V1, V1 = v + gh A1.
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    qs[j] = q[j] + gh * v[j];
    vs[j] = v[j];
    qk[j] = qs[j];
    vk[j] = v[j] + gh * a_prev[j];
  }
  compute_joint_torques(bm, qs, vs, s.tau.data(), ws);
  compute_forward_dynamics(bm, qk, vk, A1, ws);
  // Stage 2 (t + h): Q2 = q + (1-g) h V1 + gh V2, V2 = v + (1-g) h A1 + gh A2.
  const double b1 = (1.0 - g) * h;
  double* vpre = ws.v1.data();
  double* qpre = ws.q1.data();
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    qpre[j] = q[j] + b1 * (v[j] + gh * A1[j]);  // V1 = v + gh A1
    vpre[j] = v[j] + b1 * A1[j];
    qs[j] = qpre[j] + gh * vpre[j];
    vs[j] = vpre[j];
    qk[j] = qs[j];
    vk[j] = vpre[j] + gh * A1[j];
  }
  compute_joint_torques(bm, qs, vs, s.tau.data(), ws);
  compute_forward_dynamics(bm, qk, vk, A2, ws);
  // The second stage is the new state (stiffly accurate).
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    v[j] = vpre[j] + gh * A2[j];
    q[j] = qpre[j] + gh * v[j];
    a_prev[j] = A2[j];
  }
}

void step_midpoint(const BatchModel& bm, BatchState& s, Workspace& ws, double h) {
  const std::size_t n = s.q.size();
  const int W = bm.W;
  const double gh = 0.5 * h;
  // Joint armature (h/2) c + (h/2)^2 k: the implicit spring-damper terms (row 0: the hub, none).
  if (ws.armature_gh != gh) {
    for (std::size_t j = static_cast<std::size_t>(W); j < n; ++j)
      ws.armature[j] = gh * bm.joint_c[j] + gh * gh * bm.joint_k[j];
    ws.armature_gh = gh;
  }
  double* q = s.q.data();
  double* v = s.v.data();
  double* a_prev = ws.a_prev.data();
  double *qs = ws.kq[0].data(), *vk = ws.kv[0].data(), *A = ws.kv[1].data();
  // Midpoint t + h/2: V = v + (h/2) A, Q = q + (h/2) V = qs + (h/2)^2 A with qs = q + (h/2) v.
  // Springs and dampers at (qs, v) plus the armature; M and velocity terms at (qs, v + (h/2) a_prev).
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    qs[j] = q[j] + gh * v[j];
    vk[j] = v[j] + gh * a_prev[j];
  }
  compute_joint_torques(bm, qs, v, s.tau.data(), ws);
  compute_forward_dynamics(bm, qs, vk, A, ws);
  // q += h V, v += h A
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    q[j] += h * (v[j] + gh * A[j]);
    v[j] += h * A[j];
    a_prev[j] = A[j];
  }
}

}  // namespace ff
