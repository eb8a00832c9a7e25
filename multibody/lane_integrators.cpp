#include "multibody/lane_integrators.hpp"

#include <algorithm>

#include "kernel/stage_arithmetic.hpp"

namespace ff {

namespace {
std::size_t size_of(const TreeLanes& tl) { return static_cast<std::size_t>(tl.nv) * tl.W; }

// Joint armature gh c + gh^2 k of a stage with coefficient gh; remade only when gh changes.
void set_armature(const TreeLanes& tl, TreeStepWorkspace& ws, double gh) {
  if (ws.armature_gh == gh) return;
  const std::size_t n = size_of(tl);
  for (std::size_t j = 0; j < n; ++j) ws.armature[j] = gh * tl.damping[j] + gh * gh * tl.stiffness[j];
  ws.armature_gh = gh;
}

// The joint friction (TreeLanes::friction) linearly implicit, like the dampers (the reference rig
// takes its hub's so, kernel/fixed_step.cpp): the map is evaluated explicitly at the stage's rate w
// (in compute_tree_passive_forces) and its slope goes on the diagonal as armature, so the stage sees
// tau_f(w) - slope (V - w) at its own rate V. The viscous part b is exactly a damper (armature gh b,
// as the joint dampers' gh c: exact, at the method's order); the Coulomb and Stribeck part's slope
// D_c(w) (calc_coulomb_friction_damping, >= 0) takes gf D_c, gf the stage's gh (SDIRK2) or h for the
// midpoint rule (backward Euler on the steep tanh: the midpoint rule is not L-stable, and a stuck
// joint's rate would flip sign every step), so a small smoothing is stable at the step the arm needs.
// Rewrites only the friction dofs' entries, base armature included; runs before every stage.
void set_friction_armature(const TreeLanes& tl, TreeStepWorkspace& ws, const double* w, double gh, double gf) {
  const std::size_t W = static_cast<std::size_t>(tl.W);
  for (std::size_t f = 0; f < tl.friction_dofs.size(); ++f) {
    const std::size_t o = static_cast<std::size_t>(tl.friction_dofs[f]) * W;
    const FrictionMap* fm = tl.friction.data() + f * W;
    for (std::size_t l = 0; l < W; ++l) {
      const std::size_t j = o + l;
      const double base = gh * tl.damping[j] + gh * gh * tl.stiffness[j];  // set_armature's
      ws.armature[j] =
          is_friction_on(fm[l]) ? base + gh * fm[l].b + gf * calc_coulomb_friction_damping(fm[l], w[j]) : base;
    }
  }
}
}  // namespace

TreeLanesState make_tree_lanes_state(const TreeLanes& tl) {
  TreeLanesState s;
  s.q.assign(size_of(tl), 0.0);
  s.qd.assign(size_of(tl), 0.0);
  s.a_prev.assign(size_of(tl), 0.0);
  return s;
}

TreeStepWorkspace::TreeStepWorkspace(const TreeLanes& tl) : aba(tl) {
  const std::size_t n = size_of(tl);
  for (auto* v : {&q1, &qd1, &tau, &armature}) v->assign(n, 0.0);
  for (int k = 0; k < 4; ++k) kq[k].assign(n, 0.0), kv[k].assign(n, 0.0);
}

void step_tree_rk4(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws,
                   double h) {
  const std::size_t n = size_of(tl);
  double *q = s.q.data(), *qd = s.qd.data(), *q1 = ws.q1.data(), *qd1 = ws.qd1.data(), *tau = ws.tau.data();
  // Stage derivatives kq = velocity, kv = acceleration (RK4's Butcher tableau).
  const double c[4] = {0.0, 0.5 * h, 0.5 * h, h};
  for (int st = 0; st < 4; ++st) {
    const double* qs = q;
    const double* vs = qd;
    if (st > 0) {
      const double *kq = ws.kq[st - 1].data(), *kv = ws.kv[st - 1].data();
#pragma omp simd
      for (std::size_t j = 0; j < n; ++j) q1[j] = q[j] + c[st] * kq[j], qd1[j] = qd[j] + c[st] * kv[j];
      qs = q1;
      vs = qd1;
    }
    std::copy(vs, vs + n, ws.kq[st].data());
    compute_tree_passive_forces(tl, qs, vs, tau_applied, tau);
    compute_tree_forward_dynamics(tl, qs, vs, tau, nullptr, ws.kv[st].data(), ws.aba);
  }
  rk4_combine(n, ws.kq, ws.kv, h, q, qd);
}

void step_tree_midpoint(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws,
                        double h) {
  const std::size_t n = size_of(tl);
  const double gh = 0.5 * h;
  set_armature(tl, ws, gh);
  double *q = s.q.data(), *qd = s.qd.data(), *a_prev = s.a_prev.data();
  double *qs = ws.kq[0].data(), *vk = ws.kv[0].data(), *A = ws.kv[1].data(), *tau = ws.tau.data();
  // Midpoint t + h/2: V = qd + (h/2) A, Q = qs + (h/2)^2 A with qs = q + (h/2) qd.
  midpoint_stage(n, q, qd, a_prev, gh, qs, vk);
  compute_tree_passive_forces(tl, qs, qd, tau_applied, tau);
  set_friction_armature(tl, ws, qd, gh, h);
  compute_tree_forward_dynamics(tl, qs, vk, tau, ws.armature.data(), A, ws.aba);
  midpoint_finish(n, A, h, gh, q, qd, a_prev);
}

void step_tree_sdirk2(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws,
                      double h) {
  const std::size_t n = size_of(tl);
  const double g = kSdirk2Gamma;
  const double gh = g * h;
  set_armature(tl, ws, gh);
  double *q = s.q.data(), *qd = s.qd.data(), *a_prev = s.a_prev.data(), *tau = ws.tau.data();
  double *qs = ws.kq[0].data(), *vs = ws.kv[0].data();  // spring state: Qpre + gh Vpre, Vpre
  double *qk = ws.kq[1].data(), *vk = ws.kv[1].data();  // kinematic predictor of the stage
  double *A1 = ws.kq[2].data(), *A2 = ws.kv[2].data();  // stage accelerations
  double *qpre = ws.q1.data(), *vpre = ws.qd1.data();
  // Stage 1 (t + gamma h): Q1 = q + gh V1, V1 = qd + gh A1.
  sdirk2_stage1(n, q, qd, a_prev, gh, qs, vs, qk, vk);
  compute_tree_passive_forces(tl, qs, vs, tau_applied, tau);
  set_friction_armature(tl, ws, vs, gh, gh);
  compute_tree_forward_dynamics(tl, qk, vk, tau, ws.armature.data(), A1, ws.aba);
  // Stage 2 (t + h): Q2 = q + (1-g) h V1 + gh V2, V2 = qd + (1-g) h A1 + gh A2.
  sdirk2_stage2(n, q, qd, A1, gh, (1.0 - g) * h, qpre, vpre, qs, vs, qk, vk);
  compute_tree_passive_forces(tl, qs, vs, tau_applied, tau);
  set_friction_armature(tl, ws, vs, gh, gh);
  compute_tree_forward_dynamics(tl, qk, vk, tau, ws.armature.data(), A2, ws.aba);
  // The second stage is the new state (stiffly accurate).
  sdirk2_finish(n, qpre, vpre, A2, gh, q, qd, a_prev);
}

}  // namespace ff
