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

}  // namespace ff
