// The state arithmetic of the fixed-step integrators (RK4's combination; the stages of the two
// linearly implicit ones, SDIRK2 and the midpoint rule), shared by the planar chain's
// (kernel/fixed_step.cpp) and the tree's (multibody/lane_integrators.cpp), which differ only in the
// dynamics they solve at each stage. n entries of lane-innermost arrays.
//
// A stage with coefficient gh solves for the acceleration A at the state Q = qs + gh^2 A,
// V = vs + gh A: the springs and dampers are taken at (qs, vs) with the armature gh c + gh^2 k,
// M and the velocity terms at the kinematic predictor (qk, vk).
#pragma once

#include <cstddef>
#include <vector>

namespace ff {

// RK4: q += h/6 (kq0 + 2 kq1 + 2 kq2 + kq3), v likewise with the kv (stage rates and accelerations).
inline void rk4_combine(std::size_t n, const std::vector<double> (&kq)[4], const std::vector<double> (&kv)[4], double h,
                        double* q, double* v) {
  const double w6 = h / 6.0;
  const double *kq0 = kq[0].data(), *kq1 = kq[1].data(), *kq2 = kq[2].data(), *kq3 = kq[3].data();
  const double *kv0 = kv[0].data(), *kv1 = kv[1].data(), *kv2 = kv[2].data(), *kv3 = kv[3].data();
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    q[j] += w6 * (kq0[j] + 2.0 * kq1[j] + 2.0 * kq2[j] + kq3[j]);
    v[j] += w6 * (kv0[j] + 2.0 * kv1[j] + 2.0 * kv2[j] + kv3[j]);
  }
}

inline constexpr double kSdirk2Gamma = 1.0 - 0.70710678118654752440;  // Alexander (1977): 1 - 1/sqrt(2)

// SDIRK2 stage 1 (t + gamma h): Q1 = q + gh V1, V1 = v + gh A1, predictor v + gh a_prev.
inline void sdirk2_stage1(std::size_t n, const double* q, const double* v, const double* a_prev, double gh,
                          double* qs, double* vs, double* qk, double* vk) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    qs[j] = q[j] + gh * v[j];
    vs[j] = v[j];
    qk[j] = qs[j];
    vk[j] = v[j] + gh * a_prev[j];
  }
}

// SDIRK2 stage 2 (t + h): Q2 = qpre + gh V2, V2 = vpre + gh A2 with qpre = q + (1-g) h V1,
// vpre = v + (1-g) h A1 (b1 = (1-g) h), predictor vpre + gh A1.
inline void sdirk2_stage2(std::size_t n, const double* q, const double* v, const double* A1, double gh, double b1,
                          double* qpre, double* vpre, double* qs, double* vs, double* qk, double* vk) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    qpre[j] = q[j] + b1 * (v[j] + gh * A1[j]);  // V1 = v + gh A1
    vpre[j] = v[j] + b1 * A1[j];
    qs[j] = qpre[j] + gh * vpre[j];
    vs[j] = vpre[j];
    qk[j] = qs[j];
    vk[j] = vpre[j] + gh * A1[j];
  }
}

// The second stage is the new state (stiffly accurate); its acceleration the next predictor's.
inline void sdirk2_finish(std::size_t n, const double* qpre, const double* vpre, const double* A2, double gh,
                          double* q, double* v, double* a_prev) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    v[j] = vpre[j] + gh * A2[j];
    q[j] = qpre[j] + gh * v[j];
    a_prev[j] = A2[j];
  }
}

// Midpoint t + h/2 (gh = h/2): qs = q + gh v, the springs at (qs, v), predictor v + gh a_prev.
inline void midpoint_stage(std::size_t n, const double* q, const double* v, const double* a_prev, double gh,
                           double* qs, double* vk) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    qs[j] = q[j] + gh * v[j];
    vk[j] = v[j] + gh * a_prev[j];
  }
}

// q += h V, v += h A with V = v + gh A.
inline void midpoint_finish(std::size_t n, const double* A, double h, double gh, double* q, double* v,
                            double* a_prev) {
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    q[j] += h * (v[j] + gh * A[j]);
    v[j] += h * A[j];
    a_prev[j] = A[j];
  }
}

}  // namespace ff
