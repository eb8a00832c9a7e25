// Shared helpers for the kernel tests: the reference rig in code, one-lane runs, the reference trace.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "kernel/batch.hpp"
#include "kernel/model.hpp"
#include "kernel/simulate.hpp"

namespace ff::test {

// The reference rig (ModelSpec defaults) with one cubic move 0 -> target rad in 3 s, then `hold` s.
inline ModelSpec rig_spec(double target = 0.5, double hold = 17.0) {
  ModelSpec s;
  s.trajectory.moves = {{target, hold}};
  return s;
}

// Simulates one model as a one-lane batch.
inline BatchRun run_one(const Model& m) {
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  return simulate(bm);
}

// Columns of the reference trace (tests/data/reference-traces/README.md).
struct ReferenceTrace {
  std::vector<double> t, ref, hub_torque, hub_angle, tip_deflection;
};


// Loads tests/data/reference-traces/fbtb_n6_pd_0p5rad.csv.

inline ReferenceTrace load_reference_trace() {
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/reference-traces/fbtb_n6_pd_0p5rad.csv";
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::string line;
  std::getline(in, line);
  ReferenceTrace r;
  while (std::getline(in, line)) {
    double t, ref, tau, hub, defl;
    if (std::sscanf(line.c_str(), "%lf,%lf,%lf,%lf,%lf", &t, &ref, &tau, &hub, &defl) != 5)
      throw std::runtime_error("bad line in " + path + ": " + line);
    r.t.push_back(t);
    r.ref.push_back(ref);
    r.hub_torque.push_back(tau);
    r.hub_angle.push_back(hub);
    r.tip_deflection.push_back(defl);
  }
  return r;
}

// Largest |a - b| over the common length.
inline double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t k = 0; k < std::min(a.size(), b.size()); ++k) m = std::max(m, std::fabs(a[k] - b[k]));
  return m;
}

}  // namespace ff::test
