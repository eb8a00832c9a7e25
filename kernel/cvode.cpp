// CVODE (SUNDIALS 6) as the reference integrator of the batch kernel.
//
// Each lane is an independent ODE y = [q (N); v (N); z (nz)], ydot = [v; qdd; zdot](q, v, z, tau_held),
// with qdd from the articulated-body algorithm on a one-lane copy of the batch model whose tip body is
// the lane's BatchState::tip at the advance (held over it), and z the hub drive's states
// (kernel/drive.hpp: valve, oil pressures, drive train, LuGre bristles). Each lane owns its
// SUNContext, vector, matrix, linear solver and CVODE memory, and its own one-lane model and
// workspace, so lanes share no mutable state and may be advanced on different threads.
//
// Jacobians:
//  - kCvodeDense: SUNDenseMatrix + SUNLinSol_Dense with CVODE's internal difference-quotient
//    Jacobian (cvLsDenseDQJac).
//  - kCvodeKlu: SUNSparseMatrix (CSC) + SUNLinSol_KLU with our own forward-difference Jacobian,
//    one column per right-hand-side evaluation (2N evaluations of the O(N) forward dynamics).
//    Honest note: the reduced (joint-space) ODE has a Jacobian that is dense in its velocity
//    rows -- J = [[0, I], [dqdd/dq, dqdd/dv]] and M(q)^-1 couples every joint -- so KLU here runs
//    on a structurally sparse pattern of 2N^2 + N true nonzeros (plus N explicit zeros on the
//    diagonal of the top-left block, stored so that CVODE can form I - gamma*J in place without
//    SUNMatScaleAddI_Sparse reallocating the matrix). It cannot beat dense LU at this size; it
//    pays off only once sparse extra states (e.g. hydraulics, drive trains) join the system.
//
// BDF history restarts at every controller sample (CVodeReInit), because the held hub torque
// jumps there; the stop time pins the last step onto the next sample instant.
#include "kernel/cvode.hpp"

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernel/dynamics.hpp"

namespace ff {

namespace {

constexpr long kMaxStepsPerAdvance = 100000;

// One lane's solver and everything its right-hand side needs. Never moved once CVODE holds
// a pointer to it (kept behind unique_ptr).
struct Lane {
  BatchModel bm;               // one-lane copy of the lane's model
  TipLoad tip;                 // the lane's tip body over the current advance (BatchState::tip)
  BodyTable body;              // bm's bodies with `tip`
  Workspace ws;                // its articulated-body scratch
  int n = 0;                   // N
  int nz = 0;                  // hub drive states
  double tau = 0.0;            // hub torque demand held over the current advance
  std::vector<double> ypert;   // (2N + nz) perturbed state for the finite-difference Jacobian
  std::vector<double> fpert;   // (N + nz) perturbed accelerations and drive rates
  long fd_rhs_evals = 0;       // right-hand-side evaluations made by our own Jacobian
  CvodeStats totals;           // accumulated over all advances (CVODE resets its counters on ReInit)

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
};

// ydot = [v; qdd]. A non-finite result is reported as a recoverable failure so CVODE retries
// with a smaller step; at the initial point it becomes CV_FIRST_RHSFUNC_ERR.
int rhs(sunrealtype /*t*/, N_Vector y, N_Vector ydot, void* user_data) {
  Lane& L = *static_cast<Lane*>(user_data);
  const int n = L.n;
  const double* yd = N_VGetArrayPointer(y);
  double* fd = N_VGetArrayPointer(ydot);
  std::copy(yd + n, yd + 2 * n, fd);
  compute_acceleration(L.bm, L.body, yd, yd + n, yd + 2 * n, &L.tau, fd + n, fd + 2 * n, L.ws);
  for (int i = 0; i < 2 * n + L.nz; ++i)
    if (!std::isfinite(fd[i])) return 1;
  return 0;
}

// CSC pattern of J = [[0, I, 0], [dqdd/dq, dqdd/dv, dqdd/dz], [dzdot/dq, dzdot/dv, dzdot/dz]] with the
// diagonal stored in every column: column j < N holds rows {j} + {N..2N+nz-1}; column N + i holds
// rows {i} + {N..2N+nz-1}; column 2N + i holds rows {N..2N+nz-1}.
// Written on every call, because CVODE zeroes the matrix (SUNMatZero clears the pattern too).
void write_pattern(SUNMatrix A, int n, int nz) {
  sunindextype* colptrs = SUNSparseMatrix_IndexPointers(A);
  sunindextype* rowvals = SUNSparseMatrix_IndexValues(A);
  sunindextype p = 0;
  for (int j = 0; j < 2 * n + nz; ++j) {
    colptrs[j] = p;
    if (j < 2 * n) rowvals[p++] = j < n ? j : j - n;  // diagonal (q columns) or identity entry (v columns)
    for (int i = 0; i < n + nz; ++i) rowvals[p++] = n + i;
  }
  colptrs[2 * n + nz] = p;
}

// Forward-difference Jacobian for the KLU path. The top block is exact (0 and I); each column
// of the bottom block costs one forward-dynamics evaluation at y + delta_j e_j, with
// delta_j = sqrt(eps) * max(|y_j|, 1): the dynamics are nonlinear on a scale of 1 rad (sin, cos
// of the joint angles) and 1 rad/s (velocity products), so this balances truncation and rounding.
int jac_klu(sunrealtype /*t*/, N_Vector y, N_Vector fy, SUNMatrix A, void* user_data, N_Vector /*tmp1*/,
            N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
  Lane& L = *static_cast<Lane*>(user_data);
  const int n = L.n, nz = L.nz;
  const double* yd = N_VGetArrayPointer(y);
  const double* f_low = N_VGetArrayPointer(fy) + n;  // [qdd; zdot]
  double* data = SUNSparseMatrix_Data(A);
  write_pattern(A, n, nz);
  static const double srur = std::sqrt(std::numeric_limits<double>::epsilon());

  std::copy(yd, yd + 2 * n + nz, L.ypert.begin());
  double* yp = L.ypert.data();
  double* fp = L.fpert.data();
  sunindextype p = 0;
  for (int j = 0; j < 2 * n + nz; ++j) {
    // Top entry of a q or v column: 0 on the diagonal of the q block, 1 in the identity block.
    if (j < 2 * n) data[p++] = j < n ? 0.0 : 1.0;
    // Lower entries: ([qdd; zdot](y + delta e_j) - [qdd; zdot](y)) / delta, delta exactly representable.
    const double yj = yd[j];
    const double delta = (yj + srur * std::max(std::abs(yj), 1.0)) - yj;
    yp[j] = yj + delta;
    compute_acceleration(L.bm, L.body, yp, yp + n, yp + 2 * n, &L.tau, fp, fp + n, L.ws);
    ++L.fd_rhs_evals;
    yp[j] = yj;
    const double r = 1.0 / delta;
    for (int i = 0; i < n + nz; ++i) {
      const double d = (fp[i] - f_low[i]) * r;
      if (!std::isfinite(d)) return 1;  // recoverable: CVODE cuts the step and retries
      data[p++] = d;
    }
  }
  return 0;
}

// CVODE reports through this handler; advance() must never print.
void silent_error_handler(int, const char*, const char*, char*, void*) {}

[[noreturn]] void fail(const std::string& what, int lane) {
  throw std::runtime_error("CvodeBatch: " + what + " failed for lane " + std::to_string(lane));
}

// Creates lane `l`'s context, vector, matrix, linear solver and CVODE memory.
std::unique_ptr<Lane> make_lane(const BatchModel& bm, int l, Integrator kind) {
  auto L = std::make_unique<Lane>();
  L->bm = make_batch(std::span<const Model>(&bm.models[l], 1));
  L->ws = make_workspace(L->bm);
  L->tip = make_state(L->bm).tip;
  L->body = make_body_table(L->bm, L->tip);  // the Lane never moves, nor do its tip's one-lane vectors
  const int n = bm.nseg, nz = bm.layout.nz, ny = 2 * n + nz;
  L->n = n;
  L->nz = nz;
  L->ypert.assign(ny, 0.0);
  L->fpert.assign(n + nz, 0.0);
  const auto& sim = bm.models[l].spec.simulation;

  if (SUNContext_Create(nullptr, &L->ctx) != 0) fail("SUNContext_Create", l);
  L->y = N_VNew_Serial(ny, L->ctx);
  if (!L->y) fail("N_VNew_Serial", l);
  N_VConst(0.0, L->y);

  L->mem = CVodeCreate(CV_BDF, L->ctx);
  if (!L->mem) fail("CVodeCreate", l);
  if (CVodeSetErrHandlerFn(L->mem, silent_error_handler, nullptr) != CV_SUCCESS) fail("CVodeSetErrHandlerFn", l);
  if (CVodeInit(L->mem, rhs, 0.0, L->y) != CV_SUCCESS) fail("CVodeInit", l);
  if (CVodeSetUserData(L->mem, L.get()) != CV_SUCCESS) fail("CVodeSetUserData", l);
  if (CVodeSStolerances(L->mem, sim.rtol, sim.atol) != CV_SUCCESS) fail("CVodeSStolerances", l);
  if (CVodeSetMaxNumSteps(L->mem, kMaxStepsPerAdvance) != CV_SUCCESS) fail("CVodeSetMaxNumSteps", l);

  if (kind == Integrator::kCvodeKlu) {
    // Sparse CSC matrix with room for the pattern above; our own Jacobian fills it.
    const sunindextype nnz = static_cast<sunindextype>(2 * n) * (1 + n + nz) + static_cast<sunindextype>(nz) * (n + nz);
    L->A = SUNSparseMatrix(ny, ny, nnz, CSC_MAT, L->ctx);
    if (!L->A) fail("SUNSparseMatrix", l);
    L->ls = SUNLinSol_KLU(L->y, L->A, L->ctx);
    if (!L->ls) fail("SUNLinSol_KLU", l);
    if (CVodeSetLinearSolver(L->mem, L->ls, L->A) != CV_SUCCESS) fail("CVodeSetLinearSolver", l);
    if (CVodeSetJacFn(L->mem, jac_klu) != CV_SUCCESS) fail("CVodeSetJacFn", l);
  } else {
    // Dense matrix; no Jacobian function, so CVODE uses its difference-quotient Jacobian.
    L->A = SUNDenseMatrix(ny, ny, L->ctx);
    if (!L->A) fail("SUNDenseMatrix", l);
    L->ls = SUNLinSol_Dense(L->y, L->A, L->ctx);
    if (!L->ls) fail("SUNLinSol_Dense", l);
    if (CVodeSetLinearSolver(L->mem, L->ls, L->A) != CV_SUCCESS) fail("CVodeSetLinearSolver", l);
  }
  return L;
}

// Adds CVODE's counters since the last ReInit (and our own Jacobian's evaluations) to the totals.
void accumulate_stats(Lane& L) {
  long nst = 0, nfe = 0, nfe_ls = 0, nje = 0;
  CVodeGetNumSteps(L.mem, &nst);
  CVodeGetNumRhsEvals(L.mem, &nfe);
  CVodeGetNumLinRhsEvals(L.mem, &nfe_ls);
  CVodeGetNumJacEvals(L.mem, &nje);
  L.totals.steps += nst;
  L.totals.rhs_evals += nfe + nfe_ls + L.fd_rhs_evals;
  L.totals.jac_evals += nje;
  L.fd_rhs_evals = 0;
}

}  // namespace

struct CvodeBatch::Impl {
  std::vector<std::unique_ptr<Lane>> lanes;
};

CvodeBatch::CvodeBatch(const BatchModel& bm, Integrator kind) : impl_(std::make_unique<Impl>()) {
  if (kind != Integrator::kCvodeDense && kind != Integrator::kCvodeKlu)
    throw std::invalid_argument("CvodeBatch: integrator must be kCvodeDense or kCvodeKlu");
  impl_->lanes.reserve(bm.W);
  for (int l = 0; l < bm.W; ++l) impl_->lanes.push_back(make_lane(bm, l, kind));
}

CvodeBatch::~CvodeBatch() = default;

void CvodeBatch::advance(BatchState& s, double dt) {
  const int W = static_cast<int>(impl_->lanes.size());
  const double t0 = s.t, t1 = s.t + dt;
  for (int l = 0; l < W; ++l) {
    if (s.status[l] != LaneStatus::kOk) continue;
    Lane& L = *impl_->lanes[l];
    const int n = L.n;
    // Gather this lane's state (stride W) and held torque.
    double* y = N_VGetArrayPointer(L.y);
    for (int i = 0; i < n; ++i) {
      y[i] = s.q[i * W + l];
      y[n + i] = s.v[i * W + l];
    }
    for (int i = 0; i < L.nz; ++i) y[2 * n + i] = s.z[i * W + l];
    L.tau = s.tau[l];
    L.tip.mass[0] = s.tip.mass[l];
    L.tip.first[0] = s.tip.first[l];
    L.tip.inertia[0] = s.tip.inertia[l];
    // Restart the BDF history at the torque jump and integrate exactly to the next sample.
    int flag = CVodeReInit(L.mem, t0, L.y);
    if (flag >= 0) flag = CVodeSetStopTime(L.mem, t1);
    sunrealtype t = t0;
    if (flag >= 0) flag = CVode(L.mem, t1, L.y, &t, CV_NORMAL);
    accumulate_stats(L);
    if (flag < 0) {
      s.status[l] = LaneStatus::kSolverFail;  // state stays as it was at t0
      continue;
    }
    // Scatter the new state back.
    for (int i = 0; i < n; ++i) {
      s.q[i * W + l] = y[i];
      s.v[i * W + l] = y[n + i];
    }
    for (int i = 0; i < L.nz; ++i) s.z[i * W + l] = y[2 * n + i];
  }
}

CvodeStats CvodeBatch::stats() const {
  CvodeStats sum;
  for (const auto& L : impl_->lanes) {
    sum.steps += L->totals.steps;
    sum.rhs_evals += L->totals.rhs_evals;
    sum.jac_evals += L->totals.jac_evals;
  }
  return sum;
}

}  // namespace ff
