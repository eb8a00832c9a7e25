// The batch kernel's fixed-step integrators, with the hub torque held over the step. They read the
// model's parameters and advance the state; the bodies are the model's with the state's tip load
// (BatchState::tip, make_body_table).
#pragma once

#include "kernel/batch.hpp"

namespace ff {

// Advances (q, v) of every lane by one step h, s, with s.tau held (zero-order hold).
void step_rk4(const BatchModel& bm, BatchState& s, Workspace& ws, double h);

// One step of the L-stable two-stage SDIRK of Alexander (1977), gamma = 1 - 1/sqrt(2), stiffly
// accurate, second order. The joint springs and dampers, which make the chain stiff, are implicit
// and linear: each stage solves (M + diag(h gamma c + (h gamma)^2 k)) A = tau - bias with the
// articulated-body algorithm (the diagonal enters as joint armature). M and the velocity terms are
// taken at a second-order predictor of the stage state, so two ABA passes make a step at any N.
void step_sdirk2(const BatchModel& bm, BatchState& s, Workspace& ws, double h);

// One step of the implicit midpoint rule, second order, A-stable (not L-stable), linearly implicit:
// the joint springs and dampers are implicit and linear as in step_sdirk2, the single stage solves
// (M + diag(h/2 c + (h/2)^2 k)) A = tau - bias at t + h/2, then q += h (v + h/2 A), v += h A.
// M and the velocity terms at a predictor of the midpoint state: one ABA pass per step.
void step_midpoint(const BatchModel& bm, BatchState& s, Workspace& ws, double h);

}  // namespace ff
