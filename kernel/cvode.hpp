// The reference integrator: SUNDIALS CVODE, BDF with Newton iteration, with a dense or a KLU
// sparse direct linear solver. Each lane owns its own SUNContext and solver (one thread per
// solver) and is re-initialised at every controller sample, where the held torque jumps.
#pragma once

#include <memory>

#include "kernel/batch.hpp"

namespace ff {

struct CvodeStats {
  long steps = 0;          // internal steps, all lanes
  long rhs_evals = 0;      // right-hand-side evaluations
  long jac_evals = 0;      // Jacobian evaluations
};

class CvodeBatch {
 public:
  // kind: Integrator::kCvodeDense or Integrator::kCvodeKlu; tolerances from the models' simulation spec.
  CvodeBatch(const BatchModel& bm, Integrator kind);
  ~CvodeBatch();
  CvodeBatch(const CvodeBatch&) = delete;
  CvodeBatch& operator=(const CvodeBatch&) = delete;

  // Integrates every ok lane from s.t to s.t + dt with s.tau and the tip body s.tip held; a lane whose solver fails
  // is marked LaneStatus::kSolverFail and left at its last good state.
  void advance(BatchState& s, double dt);
  CvodeStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ff
