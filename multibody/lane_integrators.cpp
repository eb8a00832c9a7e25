#include "multibody/lane_integrators.hpp"

#include <algorithm>

#include "common/isa.hpp"
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
// The nonlinear drive trains (TreeLanes::transmissions) likewise: their law is evaluated at the
// stage's spring state (q, w) and its tangent (calc_transmission_tangent: k + 3 k3 e^2 and c in
// contact, 0 in the free play) goes on the twist's diagonal as gh C_t + gh^2 K_t, a spring's armature.
// Rewrites only those dofs' entries, base armature included; runs before every stage.
void set_stage_armature(const TreeLanes& tl, TreeStepWorkspace& ws, const double* q, const double* w, double gh,
                        double gf) {
  const std::size_t W = static_cast<std::size_t>(tl.W);
  const auto base = [&](std::size_t j) { return gh * tl.damping[j] + gh * gh * tl.stiffness[j]; };  // set_armature's
  for (std::size_t f = 0; f < tl.friction_dofs.size(); ++f) {
    const std::size_t o = static_cast<std::size_t>(tl.friction_dofs[f]) * W;
    const FrictionMap* fm = tl.friction.data() + f * W;
    for (std::size_t l = 0; l < W; ++l) {
      const std::size_t j = o + l;
      ws.armature[j] =
          is_friction_on(fm[l]) ? base(j) + gh * fm[l].b + gf * calc_coulomb_friction_damping(at_angle(fm[l], q[j]), w[j])
                                : base(j);
    }
  }
  for (std::size_t d = 0; d < tl.transmission_dofs.size(); ++d) {
    const std::size_t o = static_cast<std::size_t>(tl.transmission_dofs[d]) * W;
    const LaneDrive* p = tl.transmissions.data() + d * W;
    for (std::size_t l = 0; l < W; ++l) {
      const std::size_t j = o + l;
      const TransmissionTangent t = calc_transmission_tangent(p[l], q[j], w[j]);  // T odd: the same at -q_t
      ws.armature[j] = base(j) + gh * t.damping + gh * gh * t.stiffness;
    }
  }
}
std::size_t z_size_of(const TreeLanes& tl) { return static_cast<std::size_t>(tl.nz()) * tl.W; }

// The generalised force of a stage: tau_applied, or with hydraulic actuators their torques from the
// states z at (q, qd) (their rates into zdot when given).
const double* stage_force(const TreeLanes& tl, const double* q, const double* qd, const double* z,
                          const double* tau_applied, TreeStepWorkspace& ws, double* zdot) {
  if (tl.nz() == 0) return tau_applied;
  compute_tree_actuator_forces(tl, q, qd, z, tau_applied, ws.tau_act.data(), zdot);
  return ws.tau_act.data();
}

// Every state's implicit stage Z = zpre + gh f(Z), each lane's joint held at (q, qd): the hydraulic
// actuators' by simplified Newton (solve_hydraulic_stage), their command tau_applied at the joint (0
// when null); the LuGre bristles' exactly (solve_lugre_stage).
void solve_state_stages(const TreeLanes& tl, const double* q, const double* qd, const double* tau_applied,
                            const double* zpre, double gh, double* Z) {
  const std::size_t W = static_cast<std::size_t>(tl.W);
  for (std::size_t a = 0; a < tl.hydraulic_dofs.size(); ++a) {
    const std::size_t o = static_cast<std::size_t>(tl.hydraulic_dofs[a]) * W, zo = kHydraulicStates * a * W;
    for (std::size_t l = 0; l < W; ++l) {
      double x[kHydraulicStates], X[kHydraulicStates];
      for (int k = 0; k < kHydraulicStates; ++k) x[k] = zpre[zo + k * W + l];
      solve_hydraulic_stage(tl.hydraulics[a * W + l], tau_applied ? tau_applied[o + l] : 0.0, q[o + l], qd[o + l], x,
                            gh, X);
      for (int k = 0; k < kHydraulicStates; ++k) Z[zo + k * W + l] = X[k];
    }
  }
  for (std::size_t b = 0; b < tl.lugre_dofs.size(); ++b) {
    const std::size_t o = static_cast<std::size_t>(tl.lugre_dofs[b]) * W;
    const std::size_t zo = static_cast<std::size_t>(tl.bristle_row(b)) * W;
    for (std::size_t l = 0; l < W; ++l)
      Z[zo + l] = solve_lugre_stage(at_angle(tl.lugre[b * W + l], q[o + l]), tl.bristle_stiffness[b * W + l], qd[o + l],
                                    zpre[zo + l], gh);
  }
}
}  // namespace

TreeLanesState make_tree_lanes_state(const TreeLanes& tl) {
  TreeLanesState s;
  s.q.assign(size_of(tl), 0.0);
  s.qd.assign(size_of(tl), 0.0);
  s.a_prev.assign(size_of(tl), 0.0);
  s.z.assign(z_size_of(tl), 0.0);
  return s;
}

TreeStepWorkspace::TreeStepWorkspace(const TreeLanes& tl) : aba(tl) {
  const std::size_t n = size_of(tl);
  for (auto* v : {&q1, &qd1, &tau, &armature}) v->assign(n, 0.0);
  for (int k = 0; k < 4; ++k) kq[k].assign(n, 0.0), kv[k].assign(n, 0.0);
  if (tl.nz() == 0) return;
  tau_act.assign(n, 0.0);
  const std::size_t nz = z_size_of(tl);
  z1.assign(nz, 0.0);
  for (auto& k : kz) k.assign(nz, 0.0);
}

static void step_tree_rk4_kernel(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s,
                                 TreeStepWorkspace& ws, double h) {
  const std::size_t n = size_of(tl);
  double *q = s.q.data(), *qd = s.qd.data(), *q1 = ws.q1.data(), *qd1 = ws.qd1.data(), *tau = ws.tau.data();
  // Stage derivatives kq = velocity, kv = acceleration (RK4's Butcher tableau).
  const double c[4] = {0.0, 0.5 * h, 0.5 * h, h};
  const std::size_t nz = z_size_of(tl);
  double *z = s.z.data(), *z1 = ws.z1.data();
  for (int st = 0; st < 4; ++st) {
    const double* qs = q;
    const double* vs = qd;
    const double* zs = z;
    if (st > 0) {
      const double *kq = ws.kq[st - 1].data(), *kv = ws.kv[st - 1].data();
#pragma omp simd
      for (std::size_t j = 0; j < n; ++j) q1[j] = q[j] + c[st] * kq[j], qd1[j] = qd[j] + c[st] * kv[j];
      const double* kz = nz ? ws.kz[st - 1].data() : nullptr;
      for (std::size_t j = 0; j < nz; ++j) z1[j] = z[j] + c[st] * kz[j];
      qs = q1;
      vs = qd1;
      zs = z1;
    }
    std::copy(vs, vs + n, ws.kq[st].data());
    const double* force = stage_force(tl, qs, vs, zs, tau_applied, ws, nz ? ws.kz[st].data() : nullptr);
    compute_tree_passive_forces(tl, qs, vs, force, tau);
    compute_tree_forward_dynamics(tl, qs, vs, tau, nullptr, ws.kv[st].data(), ws.aba);
  }
  rk4_combine(n, ws.kq, ws.kv, h, q, qd);
  if (nz == 0) return;
  const double w6 = h / 6.0;
  const double *kz0 = ws.kz[0].data(), *kz1 = ws.kz[1].data(), *kz2 = ws.kz[2].data(), *kz3 = ws.kz[3].data();
  for (std::size_t j = 0; j < nz; ++j) z[j] += w6 * (kz0[j] + 2.0 * kz1[j] + 2.0 * kz2[j] + kz3[j]);
}
FF_ISA_DISPATCH(void, step_tree_rk4,
                (const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws, double h),
                (tl, tau_applied, s, ws, h))

static void step_tree_midpoint_kernel(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s,
                                      TreeStepWorkspace& ws, double h) {
  const std::size_t n = size_of(tl);
  const double gh = 0.5 * h;
  set_armature(tl, ws, gh);
  double *q = s.q.data(), *qd = s.qd.data(), *a_prev = s.a_prev.data();
  double *qs = ws.kq[0].data(), *vk = ws.kv[0].data(), *A = ws.kv[1].data(), *tau = ws.tau.data();
  // Midpoint t + h/2: V = qd + (h/2) A, Q = qs + (h/2)^2 A with qs = q + (h/2) qd.
  midpoint_stage(n, q, qd, a_prev, gh, qs, vk);
  // The actuators by the implicit midpoint rule: Z = z + (h/2) f(Z), z_new = 2 Z - z.
  const double* force = tau_applied;
  if (const std::size_t nz = z_size_of(tl); nz > 0) {
    double *z = s.z.data(), *Z = ws.z1.data();
    solve_state_stages(tl, qs, vk, tau_applied, z, gh, Z);
    force = stage_force(tl, qs, vk, Z, tau_applied, ws, nullptr);
    for (std::size_t j = 0; j < nz; ++j) z[j] = 2.0 * Z[j] - z[j];
  }
  compute_tree_passive_forces(tl, qs, qd, force, tau);
  set_stage_armature(tl, ws, qs, qd, gh, h);
  compute_tree_forward_dynamics(tl, qs, vk, tau, ws.armature.data(), A, ws.aba);
  midpoint_finish(n, A, h, gh, q, qd, a_prev);
}
FF_ISA_DISPATCH(void, step_tree_midpoint,
                (const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws, double h),
                (tl, tau_applied, s, ws, h))

static void step_tree_sdirk2_kernel(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s,
                                    TreeStepWorkspace& ws, double h) {
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
  // The actuators' stages (implicit, the joints at the spring state), then their torques.
  const std::size_t nz = z_size_of(tl);
  double *z = s.z.data(), *Z1 = ws.z1.data(), *Z2 = nz ? ws.kz[0].data() : nullptr, *zpre = nz ? ws.kz[1].data() : nullptr;
  if (nz) solve_state_stages(tl, qk, vk, tau_applied, z, gh, Z1);
  const double* force = stage_force(tl, qk, vk, Z1, tau_applied, ws, nullptr);
  compute_tree_passive_forces(tl, qs, vs, force, tau);
  set_stage_armature(tl, ws, qs, vs, gh, gh);
  compute_tree_forward_dynamics(tl, qk, vk, tau, ws.armature.data(), A1, ws.aba);
  // Stage 2 (t + h): Q2 = q + (1-g) h V1 + gh V2, V2 = qd + (1-g) h A1 + gh A2.
  const double b1 = (1.0 - g) * h;
  sdirk2_stage2(n, q, qd, A1, gh, b1, qpre, vpre, qs, vs, qk, vk);
  // Actuators: Z2 = z + (1-g) h F1 + gh f(Z2), F1 = (Z1 - z) / gh from the first stage.
  if (nz) {
    for (std::size_t j = 0; j < nz; ++j) zpre[j] = z[j] + b1 * (Z1[j] - z[j]) / gh;
    solve_state_stages(tl, qk, vk, tau_applied, zpre, gh, Z2);
    std::copy(Z2, Z2 + nz, z);
  }
  force = stage_force(tl, qk, vk, z, tau_applied, ws, nullptr);
  compute_tree_passive_forces(tl, qs, vs, force, tau);
  set_stage_armature(tl, ws, qs, vs, gh, gh);
  compute_tree_forward_dynamics(tl, qk, vk, tau, ws.armature.data(), A2, ws.aba);
  // The second stage is the new state (stiffly accurate).
  sdirk2_finish(n, qpre, vpre, A2, gh, q, qd, a_prev);
}
FF_ISA_DISPATCH(void, step_tree_sdirk2,
                (const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, TreeStepWorkspace& ws, double h),
                (tl, tau_applied, s, ws, h))

}  // namespace ff
