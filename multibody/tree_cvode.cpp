#include "multibody/tree_cvode.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "multibody/algorithms.hpp"

namespace ff {

namespace {

using Eigen::Map;
using Eigen::VectorXd;

// One lane's solver and everything its right-hand side needs. Never moved once CVODE holds a
// pointer to it (kept behind unique_ptr).
struct Lane {
  Tree tree;                // the lane's own copy
  TreeWorkspace ws;
  TreeLanes one;            // the lane alone (extract_tree_lane): its passive laws and states z
  int nv = 0;
  VectorXd tau_held;        // (nv) the applied force over the current advance (an actuator's command at its dof)
  VectorXd tau_act;         // (nv) scratch: tau_held with the states' forces (compute_tree_actuator_forces)
  VectorXd tau;             // (nv) scratch: that plus the passive forces
  int nz = 0;               // the states z after q and qd in y (TreeLanes::nz)
  std::vector<double> pjac; // (actuators x 16) kGmres: each actuator's df/dz at the preconditioner's setup
  VectorXd ypert, fpert;    // (2 nv + nz) the finite-difference Jacobian's perturbed state and rate
  long fd_rhs_evals = 0;    // right-hand sides of our own Jacobian since the last ReInit

  // kGmres's preconditioner: the lane as one lane without gravity, its ABA with armature.
  TreeLanes pre;
  TreeLanesWorkspace pre_ws;
  std::vector<double> k, c;             // (nv) scratch: the springs and dampers of the current solve
  std::vector<double> zero, D, w, out;  // (nv) qd = 0, gamma c + gamma^2 k, right-hand side, solution

  // Where the last successful advance ended, for continuing without ReInit.
  bool live = false;        // CVODE holds a history that ends at (t_end, y_end) under tau_end
  double t_end = 0.0;
  VectorXd tau_end;

  long steps_done = 0, rhs_done = 0;  // totals before the last ReInit (CVODE's counters restart there)

  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver ls = nullptr;
  void* mem = nullptr;

  Lane() = default;
  Lane(const Lane&) = delete;
  Lane& operator=(const Lane&) = delete;
  ~Lane() {
    if (mem) CVodeFree(&mem);
    if (ls) SUNLinSolFree(ls);
    if (A) SUNMatDestroy(A);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }

  long cvode_steps() const {
    long n = 0;
    CVodeGetNumSteps(mem, &n);
    return n;
  }
  long cvode_rhs() const {
    long nfe = 0, nfe_ls = 0;
    CVodeGetNumRhsEvals(mem, &nfe);
    CVodeGetNumLinRhsEvals(mem, &nfe_ls);
    return nfe + nfe_ls + fd_rhs_evals;
  }
};

// f = [qd; qdd; z'](y). Returns false when anything is not finite.
bool eval(Lane& L, const double* y, double* f) {
  const int n = L.nv;
  const Map<const VectorXd> q(y, n), qd(y + n, n);
  Map<VectorXd> qdd(f + n, n);
  const double* force = L.tau_held.data();
  if (L.nz > 0) {  // y and f hold the states z after q and qd
    compute_tree_actuator_forces(L.one, y, y + n, y + 2 * n, force, L.tau_act.data(), f + 2 * n);
    force = L.tau_act.data();
  }
  compute_tree_passive_forces(L.one, y, y + n, force, L.tau.data());
  calc_forward_dynamics(L.tree, q, qd, L.tau, qdd, L.ws);
  std::copy(y + n, y + 2 * n, f);
  for (int i = 0; i < 2 * n + L.nz; ++i)
    if (!std::isfinite(f[i])) return false;
  return true;
}

// A non-finite rate is a recoverable failure (CVODE retries with a smaller step); at the initial
// point it becomes CV_FIRST_RHSFUNC_ERR.
int rhs(sunrealtype /*t*/, N_Vector y, N_Vector ydot, void* user_data) {
  Lane& L = *static_cast<Lane*>(user_data);
  return eval(L, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot)) ? 0 : 1;
}

// CSC pattern of J = [[0, I, 0], [dqdd/dq, dqdd/dqd, dqdd/dz], [dz'/dq, dz'/dqd, dz'/dz]] (z the nz
// actuator states, none without): column j < nv holds rows {j} + {nv .. 2nv+nz-1} (the diagonal stored
// as an explicit zero), column nv + i holds rows {i} + {nv .. 2nv+nz-1}, column 2nv + k rows
// {nv .. 2nv+nz-1}. Written on every call, because CVODE zeroes the matrix (SUNMatZero clears the
// pattern too).
void write_pattern(SUNMatrix A, int n, int nz) {
  sunindextype* colptrs = SUNSparseMatrix_IndexPointers(A);
  sunindextype* rowvals = SUNSparseMatrix_IndexValues(A);
  sunindextype p = 0;
  for (int j = 0; j < 2 * n + nz; ++j) {
    colptrs[j] = p;
    if (j < 2 * n) rowvals[p++] = j < n ? j : j - n;
    for (int i = 0; i < n + nz; ++i) rowvals[p++] = n + i;
  }
  colptrs[2 * n + nz] = p;
}

// Forward-difference Jacobian for KLU: the top block exact (0 and I); each column of the bottom
// block one forward-dynamics pass at y + delta_j e_j, delta_j = sqrt(eps) max(|y_j|, 1) (the
// dynamics are nonlinear on a scale of 1 rad and 1 rad/s), made exactly representable.
int jac_klu(sunrealtype /*t*/, N_Vector y, N_Vector fy, SUNMatrix A, void* user_data, N_Vector /*tmp1*/,
            N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
  Lane& L = *static_cast<Lane*>(user_data);
  const int n = L.nv, nz = L.nz;
  const double* yd = N_VGetArrayPointer(y);
  const double* f_low = N_VGetArrayPointer(fy) + n;
  double* data = SUNSparseMatrix_Data(A);
  write_pattern(A, n, nz);
  static const double srur = std::sqrt(std::numeric_limits<double>::epsilon());
  double* yp = L.ypert.data();
  double* fp = L.fpert.data();
  std::copy(yd, yd + 2 * n + nz, yp);
  sunindextype p = 0;
  for (int j = 0; j < 2 * n + nz; ++j) {
    if (j < 2 * n) data[p++] = j < n ? 0.0 : 1.0;
    const double yj = yd[j];
    const double delta = (yj + srur * std::max(std::abs(yj), 1.0)) - yj;
    yp[j] = yj + delta;
    const bool finite = eval(L, yp, fp);
    ++L.fd_rhs_evals;
    yp[j] = yj;
    if (!finite) return 1;  // recoverable: CVODE cuts the step and retries
    const double r = 1.0 / delta;
    for (int i = 0; i < n + nz; ++i) data[p++] = (fp[n + i] - f_low[i]) * r;
  }
  return 0;
}

// kGmres's preconditioner P = I - gamma [[0, I], [-M^-1 K, -M^-1 C]] (K, C: the joint springs and
// dampers, the stiff part of the Jacobian, with the joint friction's slope and the drive trains'
// tangents at y; gravity, velocity products and dM/dq left out). P z = r:
//   (M + D) w = -D r_v - gamma K r_q,  z_v = r_v + w,  z_q = r_q + gamma z_v,  D = gamma C + gamma^2 K,
// one ABA pass with D as extra armature (no gravity, qd = 0), O(nv). The states z (block Jacobi):
// (I - gamma dz'/dz) z_z = r_z per actuator, dz'/dz by forward differences at the setup's y with its
// joint held (calc_hydraulic_jacobian), a 4 x 4 solve; per LuGre bristle the 1 x 1 block, its rate
// being linear in z.
int psetup(sunrealtype, N_Vector y, N_Vector, sunbooleantype jok, sunbooleantype* jcur, sunrealtype, void* user_data) {
  Lane& L = *static_cast<Lane*>(user_data);
  *jcur = SUNTRUE;
  if (jok && !L.one.hydraulic_dofs.empty()) {
    *jcur = SUNFALSE;
    return 0;
  }
  const double* yd = N_VGetArrayPointer(y);
  const int n = L.nv;
  for (std::size_t a = 0; a < L.one.hydraulic_dofs.size(); ++a) {
    const int dof = L.one.hydraulic_dofs[a];
    double f0[kHydraulicStates];
    calc_hydraulic_jacobian(L.one.hydraulics[a], L.tau_held[dof], yd[dof], yd[n + dof], yd + 2 * n + kHydraulicStates * a,
                            f0, L.pjac.data() + kHydraulicStates * kHydraulicStates * a);
  }
  return 0;
}

int psolve(sunrealtype /*t*/, N_Vector y, N_Vector /*fy*/, N_Vector r, N_Vector z, sunrealtype gamma,
           sunrealtype /*delta*/, int /*lr*/, void* user_data) {
  Lane& L = *static_cast<Lane*>(user_data);
  const TreeLanes& one = L.one;
  const int n = L.nv;
  const double* yd = N_VGetArrayPointer(y);
  const double* rd = N_VGetArrayPointer(r);
  double* zd = N_VGetArrayPointer(z);
  L.k = one.stiffness;
  L.c = one.damping;
  // The joint friction's slope at the current rate, a damper like C; the drive trains' tangents.
  for (std::size_t f = 0; f < one.friction_dofs.size(); ++f)
    if (is_friction_on(one.friction[f])) {
      const int d = one.friction_dofs[f];
      L.c[static_cast<std::size_t>(d)] += calc_friction_damping(at_angle(one.friction[f], yd[d]), yd[n + d]);
    }
  for (std::size_t t = 0; t < one.transmission_dofs.size(); ++t) {
    const int d = one.transmission_dofs[t];
    const TransmissionTangent tan = calc_transmission_tangent(one.transmissions[t], yd[d], yd[n + d]);
    L.k[static_cast<std::size_t>(d)] += tan.stiffness;
    L.c[static_cast<std::size_t>(d)] += tan.damping;
  }
  for (int i = 0; i < n; ++i) {
    const std::size_t j = static_cast<std::size_t>(i);
    L.D[j] = gamma * L.c[j] + gamma * gamma * L.k[j];
    L.w[j] = -L.D[j] * rd[n + i] - gamma * L.k[j] * rd[i];
  }
  compute_tree_forward_dynamics(L.pre, yd, L.zero.data(), L.w.data(), L.D.data(), L.out.data(), L.pre_ws);
  for (int i = 0; i < n; ++i) {
    zd[n + i] = rd[n + i] + L.out[static_cast<std::size_t>(i)];
    zd[i] = rd[i] + gamma * zd[n + i];
  }
  constexpr int m = kHydraulicStates;
  for (std::size_t a = 0; a < one.hydraulic_dofs.size(); ++a) {
    const std::size_t o = 2 * static_cast<std::size_t>(n) + m * a;
    const double* J = L.pjac.data() + m * m * a;
    double P[m * m];
    for (int i = 0; i < m * m; ++i) P[i] = (i % (m + 1) == 0 ? 1.0 : 0.0) - gamma * J[i];
    std::copy(rd + o, rd + o + m, zd + o);
    solve_small_system(m, P, zd + o);
  }
  for (std::size_t b = 0; b < one.lugre_dofs.size(); ++b) {
    const std::size_t o = 2 * static_cast<std::size_t>(n) + static_cast<std::size_t>(one.bristle_row(b));
    const double w = yd[n + one.lugre_dofs[b]];
    const FrictionMap f = at_angle(one.lugre[b], yd[one.lugre_dofs[b]]);
    const double dzdz = calc_lugre_bristle_rate(f, one.bristle_stiffness[b], w, 1.0) -
                        calc_lugre_bristle_rate(f, one.bristle_stiffness[b], w, 0.0);
    zd[o] = rd[o] / (1.0 - gamma * dzdz);
  }
  for (int i = 0; i < 2 * n + L.nz; ++i)
    if (!std::isfinite(zd[i])) return 1;  // recoverable
  return 0;
}

// CVODE reports through this handler; advance() must never print.
void silent_error_handler(int, const char*, const char*, char*, void*) {}

[[noreturn]] void fail(const std::string& what, int lane) {
  throw std::runtime_error("TreeCvode: " + what + " failed for lane " + std::to_string(lane));
}

std::unique_ptr<Lane> make_lane(const TreeLanes& tl, int l, const TreeCvodeOptions& opt) {
  auto L = std::make_unique<Lane>();
  L->tree = tl.trees[static_cast<std::size_t>(l)];
  L->ws = TreeWorkspace(L->tree);
  L->one = extract_tree_lane(tl, l);
  L->nz = tl.nz();
  L->pjac.assign(tl.hydraulic_dofs.size() * kHydraulicStates * kHydraulicStates, 0.0);
  const int n = tl.nv, ny = 2 * n + L->nz;
  L->nv = n;
  L->tau_held = VectorXd::Zero(n);
  L->tau_act = VectorXd::Zero(n);
  L->tau = VectorXd::Zero(n);
  L->tau_end = VectorXd::Zero(n);
  L->ypert = VectorXd::Zero(ny);
  L->fpert = VectorXd::Zero(ny);

  if (SUNContext_Create(nullptr, &L->ctx) != 0) fail("SUNContext_Create", l);
  L->y = N_VNew_Serial(ny, L->ctx);
  if (!L->y) fail("N_VNew_Serial", l);
  N_VConst(0.0, L->y);
  L->mem = CVodeCreate(CV_BDF, L->ctx);
  if (!L->mem) fail("CVodeCreate", l);
  if (CVodeSetErrHandlerFn(L->mem, silent_error_handler, nullptr) != CV_SUCCESS) fail("CVodeSetErrHandlerFn", l);
  if (CVodeInit(L->mem, rhs, 0.0, L->y) != CV_SUCCESS) fail("CVodeInit", l);
  if (CVodeSetUserData(L->mem, L.get()) != CV_SUCCESS) fail("CVodeSetUserData", l);
  if (CVodeSStolerances(L->mem, opt.rtol, opt.atol) != CV_SUCCESS) fail("CVodeSStolerances", l);
  if (CVodeSetMaxNumSteps(L->mem, opt.max_steps) != CV_SUCCESS) fail("CVodeSetMaxNumSteps", l);

  if (opt.solver == TreeCvodeSolver::kKlu) {
    const sunindextype nnz = static_cast<sunindextype>(2 * n) * (n + 1 + L->nz) + static_cast<sunindextype>(L->nz) * (n + L->nz);
    L->A = SUNSparseMatrix(ny, ny, nnz, CSC_MAT, L->ctx);
    if (!L->A) fail("SUNSparseMatrix", l);
    L->ls = SUNLinSol_KLU(L->y, L->A, L->ctx);
    if (!L->ls) fail("SUNLinSol_KLU", l);
    if (CVodeSetLinearSolver(L->mem, L->ls, L->A) != CV_SUCCESS) fail("CVodeSetLinearSolver", l);
    if (CVodeSetJacFn(L->mem, jac_klu) != CV_SUCCESS) fail("CVodeSetJacFn", l);
  } else if (opt.solver == TreeCvodeSolver::kGmres) {
    L->pre = L->one;
    std::fill(L->pre.gravity.begin(), L->pre.gravity.end(), 0.0);
    L->pre_ws = TreeLanesWorkspace(L->pre);
    for (auto* v : {&L->k, &L->c, &L->zero, &L->D, &L->w, &L->out}) v->assign(static_cast<std::size_t>(n), 0.0);
    L->ls = SUNLinSol_SPGMR(L->y, SUN_PREC_LEFT, 0, L->ctx);
    if (!L->ls) fail("SUNLinSol_SPGMR", l);
    if (CVodeSetLinearSolver(L->mem, L->ls, nullptr) != CV_SUCCESS) fail("CVodeSetLinearSolver", l);
    if (CVodeSetPreconditioner(L->mem, psetup, psolve) != CV_SUCCESS) fail("CVodeSetPreconditioner", l);
  } else {
    L->A = SUNDenseMatrix(ny, ny, L->ctx);
    if (!L->A) fail("SUNDenseMatrix", l);
    L->ls = SUNLinSol_Dense(L->y, L->A, L->ctx);
    if (!L->ls) fail("SUNLinSol_Dense", l);
    if (CVodeSetLinearSolver(L->mem, L->ls, L->A) != CV_SUCCESS) fail("CVodeSetLinearSolver", l);
  }
  return L;
}

}  // namespace

struct TreeCvode::Impl {
  int W = 0, nv = 0;
  std::vector<std::unique_ptr<Lane>> lanes;
  const Lane& lane(int l) const {
    if (l < 0 || l >= W) throw std::out_of_range("TreeCvode: lane " + std::to_string(l) + " out of range");
    return *lanes[static_cast<std::size_t>(l)];
  }
};

TreeCvode::TreeCvode(const TreeLanes& tl, const TreeCvodeOptions& opt) : impl_(std::make_unique<Impl>()) {
  if (!(opt.rtol > 0.0) || !std::isfinite(opt.rtol) || !(opt.atol > 0.0) || !std::isfinite(opt.atol))
    throw std::invalid_argument("TreeCvode: rtol and atol must be positive and finite");
  if (opt.max_steps <= 0) throw std::invalid_argument("TreeCvode: max_steps must be positive");
  if (tl.W <= 0 || static_cast<int>(tl.trees.size()) != tl.W)
    throw std::invalid_argument("TreeCvode: the lanes hold no trees");
  impl_->W = tl.W;
  impl_->nv = tl.nv;
  impl_->lanes.reserve(static_cast<std::size_t>(tl.W));
  for (int l = 0; l < tl.W; ++l) impl_->lanes.push_back(make_lane(tl, l, opt));
}

TreeCvode::~TreeCvode() = default;

void TreeCvode::advance(const TreeLanes& tl, const double* tau_applied, TreeLanesState& s, double t, double dt,
                        std::vector<char>& ok) {
  const int W = impl_->W, n = impl_->nv;
  if (tl.W != W || tl.nv != n) throw std::invalid_argument("TreeCvode: lanes of another shape than it was made for");
  const std::size_t size = static_cast<std::size_t>(n) * W;
  if (s.q.size() != size || s.qd.size() != size || s.a_prev.size() != size ||
      s.z.size() != static_cast<std::size_t>(tl.nz()) * W)
    throw std::invalid_argument("TreeCvode: state vectors are not nv x W (z: nz x W)");
  if (!std::isfinite(t) || !std::isfinite(dt) || dt < 0.0)
    throw std::invalid_argument("TreeCvode: t and dt must be finite, dt >= 0");
  ok.assign(static_cast<std::size_t>(W), 1);
  if (dt == 0.0 || n == 0) return;
  const double t1 = t + dt;
  for (int l = 0; l < W; ++l) {
    Lane& L = *impl_->lanes[static_cast<std::size_t>(l)];
    double* y = N_VGetArrayPointer(L.y);
    // Gather the lane's state (stride W) and held force; continue CVODE's history only when nothing
    // differs from where it stopped.
    bool same = L.live && t == L.t_end;
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) * W + l;
      const double tau_i = tau_applied ? tau_applied[k] : 0.0;
      same = same && s.q[k] == y[i] && s.qd[k] == y[n + i] && tau_i == L.tau_end[i];
      y[i] = s.q[k];
      y[n + i] = s.qd[k];
      L.tau_held[i] = tau_i;
    }
    for (int i = 0; i < L.nz; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) * W + l;
      same = same && s.z[k] == y[2 * n + i];
      y[2 * n + i] = s.z[k];
    }
    int flag = CV_SUCCESS;
    if (!same) {
      L.steps_done += L.cvode_steps();
      L.rhs_done += L.cvode_rhs();
      L.fd_rhs_evals = 0;
      flag = CVodeReInit(L.mem, t, L.y);
    }
    if (flag >= 0) flag = CVodeSetStopTime(L.mem, t1);
    sunrealtype tret = t;
    if (flag >= 0) flag = CVode(L.mem, t1, L.y, &tret, CV_NORMAL);
    if (flag < 0) {
      ok[static_cast<std::size_t>(l)] = 0;  // s keeps the lane's state at t
      L.live = false;
      continue;
    }
    L.live = true;
    L.t_end = t1;
    L.tau_end = L.tau_held;
    // Scatter the new state and its accelerations (one more forward-dynamics pass, outside CVODE).
    eval(L, y, L.fpert.data());
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) * W + l;
      s.q[k] = y[i];
      s.qd[k] = y[n + i];
      s.a_prev[k] = L.fpert[n + i];
    }
    for (int i = 0; i < L.nz; ++i) s.z[static_cast<std::size_t>(i) * W + l] = y[2 * n + i];
  }
}

long TreeCvode::steps(int lane) const {
  const Lane& L = impl_->lane(lane);
  return L.steps_done + L.cvode_steps();
}

long TreeCvode::rhs_evals(int lane) const {
  const Lane& L = impl_->lane(lane);
  return L.rhs_done + L.cvode_rhs();
}

}  // namespace ff
