// The batch kernel's fixed-step integrator: classical Runge-Kutta 4 with the hub torque held.
#pragma once

#include "kernel/batch.hpp"

namespace ff {

// Advances (q, v) of every lane by one step h, s, with s.tau held (zero-order hold).
void step_rk4(const BatchModel& bm, BatchState& s, Workspace& ws, double h);

}  // namespace ff
