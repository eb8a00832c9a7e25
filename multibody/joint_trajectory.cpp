// Rest-to-rest joint trajectories (joint_trajectory.hpp).
#include "multibody/joint_trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <stdexcept>
#include <string>

namespace ff {

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("joint trajectory: " + what); }

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(9);
  o << v;
  return o.str();
}

bool all_finite(const std::vector<double>& v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// The hold at q_hold: q = q_hold, qd = qdd = 0.
void hold(const std::vector<double>& q_hold, double* q, double* qd, double* qdd) {
  const std::size_t n = q_hold.size();
  for (std::size_t j = 0; j < n; ++j) {
    q[j] = q_hold[j];
    qd[j] = 0.0;
    qdd[j] = 0.0;
  }
}

}  // namespace

void eval_joint_trajectory(const JointTrajectory& tr, double t, double* q, double* qd, double* qdd) {
  const std::vector<JointWaypoint>& wp = tr.waypoints;
  if (wp.empty()) return hold(tr.start, q, qd, qdd);
  if (!(t < wp.back().time)) return hold(wp.back().q, q, qd, qdd);  // also NaN
  if (t < 0.0) return hold(tr.start, q, qd, qdd);
  // Segment k: the first waypoint arriving after t (so at a waypoint's time, the next segment).
  const auto it = std::upper_bound(wp.begin(), wp.end(), t,
                                   [](double tt, const JointWaypoint& p) { return tt < p.time; });
  const std::size_t k = static_cast<std::size_t>(it - wp.begin());
  const double ta = k == 0 ? 0.0 : wp[k - 1].time;
  const std::vector<double>& qa = k == 0 ? tr.start : wp[k - 1].q;
  const std::vector<double>& qb = wp[k].q;
  const double inv_T = 1.0 / (wp[k].time - ta);
  const double u = (t - ta) * inv_T;  // in [0, 1)
  // Both shapes are point-symmetric, s(u) = 1 - s(1 - u), so the second half is evaluated from q_b
  // at w = 1 - u: q = q_b - d s(w), and s'(u) = s'(w), s''(u) = -s''(w). Each waypoint is then
  // approached without the round-off of q_a + d s at s -> 1 (or the quintic's cancellation there).
  const bool second_half = u > 0.5;
  const double w = second_half ? 1.0 - u : u;  // in [0, 1/2]
  const double sign = second_half ? -1.0 : 1.0;
  const double* base = second_half ? qb.data() : qa.data();
  // f = ±s(w), sd = s'(w)/T, sdd = ±s''(w)/T².
  double f, sd, sdd;
  if (tr.shape == TrajectoryShape::kCubic) {
    f = sign * w * w * (3.0 - 2.0 * w);
    sd = 6.0 * w * (1.0 - w) * inv_T;
    sdd = sign * (6.0 - 12.0 * w) * inv_T * inv_T;
  } else {
    const double w2 = w * w;
    f = sign * w2 * w * (10.0 + w * (-15.0 + 6.0 * w));
    sd = 30.0 * w2 * (1.0 - w) * (1.0 - w) * inv_T;
    sdd = sign * 60.0 * w * (1.0 + w * (-3.0 + 2.0 * w)) * inv_T * inv_T;
  }
  const std::size_t n = qa.size();
  for (std::size_t j = 0; j < n; ++j) {
    const double d = qb[j] - qa[j];
    q[j] = base[j] + d * f;
    qd[j] = d * sd;
    qdd[j] = d * sdd;
  }
}

void check_joint_trajectory(const JointTrajectory& tr) {
  if (!all_finite(tr.start)) fail("start has a non-finite value");
  if (tr.waypoints.empty()) fail("no waypoints (a trajectory needs at least one)");
  double prev = 0.0;
  for (std::size_t k = 0; k < tr.waypoints.size(); ++k) {
    const JointWaypoint& p = tr.waypoints[k];
    const std::string wk = "waypoint " + std::to_string(k) + ": ";
    if (p.q.size() != tr.start.size())
      fail(wk + "has " + std::to_string(p.q.size()) + " joint values, start has " + std::to_string(tr.start.size()));
    if (!all_finite(p.q)) fail(wk + "has a non-finite joint value");
    if (!std::isfinite(p.time)) fail(wk + "time is not finite");
    if (!(p.time > prev))
      fail(wk + "time " + fmt(p.time) + " s is not after " +
           (k == 0 ? std::string("the start (t = 0)") : "waypoint " + std::to_string(k - 1) + "'s " + fmt(prev) + " s"));
    prev = p.time;
  }
}

}  // namespace ff
