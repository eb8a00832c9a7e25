// Arm metrics (arm_metrics.hpp).
#include "arm/arm_metrics.hpp"

#include <algorithm>
#include <cmath>

#include "kernel/metrics.hpp"

namespace ff {

std::vector<std::string> arm_metric_columns(const ArmModel& m) {
  std::vector<std::string> c;
  for (const ActuatedJoint& a : m.actuated)
    for (const char* s : {"_settling_s", "_overshoot_pct", "_peak_torque_Nm", "_peak_speed"}) c.push_back(a.name + s);
  for (const ArmTool& t : m.tools)
    for (const char* s : kToolMetricSuffixes) c.push_back(t.name + s);
  for (const LinkTip& l : m.links)
    for (const char* s : {"_peak_deflection_m", "_residual_m", "_sag_m"}) c.push_back(l.name + s);
  if (m.collision.active()) {
    for (const char* s : {"min_clearance_m", "min_clearance_time_s", "first_contact_s", "contacts", "contact"}) c.push_back(s);
    for (const std::string& p : m.collision.parts) c.push_back(p + "_clearance_m");
    for (const Obstacle& o : m.collision.world.obstacles) c.push_back(o.name + "_clearance_m");
  }
  if (!m.monitors.empty()) {
    for (const ArmMonitor& o : m.monitors) c.push_back(o.name + "_trip_s");
    for (const char* s : {"trip_s", "trip_cause", "stopping_distance_m", "stop_time_s"}) c.push_back(s);
  }
  c.push_back("settling_horizon_s");
  return c;
}

namespace {

double peak_abs(const std::vector<double>& y) {
  double p = 0.0;
  for (double v : y) p = std::max(p, std::abs(v));
  return p;
}

// Last exit of e(t) >= 0 from [0, band] after t0, interpolated, less t0; NaN (not settled) when it is
// out at the end or has not stayed in for `dwell` before the end.
double last_exit(std::span<const double> t, const std::vector<double>& e, double t0, double band, double dwell) {
  std::size_t last = t.size();
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= t0 && e[k] > band) last = k;
  if (last == t.size()) return 0.0;
  if (last + 1 == t.size()) return std::nan("");
  return calc_arm_exit_time(t[last], e[last], t[last + 1], e[last + 1], band, t0, t.back(), dwell);
}

}  // namespace

ArmSettleRule make_arm_settle_rule(const ArmModel& m) {
  // The dwell: one period of the slowest closed-loop resonance (the reference rig's rule,
  // results/run_metrics.hpp), 1 s without one.
  return {m.move_end, m.spec.band, m.spec.tool_band, m.resonances.empty() ? 1.0 : 2.0 * M_PI / m.resonances.front()};
}

ArmJointMoves calc_arm_joint_moves(const ArmModel& m, std::size_t j) {
  double largest = 0.0, start = m.trajectory.start[j], from = start, target = start, t_from = 0.0, t_start = 0.0;
  for (const JointWaypoint& w : m.trajectory.waypoints) {
    const double step = w.q[j] - from;
    if (std::abs(step) > kArmMoveTolerance) {
      largest = std::max(largest, std::abs(step));
      start = from, target = w.q[j], t_start = t_from;
    }
    from = w.q[j];
    t_from = w.time;
  }
  return {largest, start, target, from, t_start};
}

double calc_arm_last_move_start(const ArmModel& m) {
  double t = 0.0;
  for (std::size_t j = 0; j < m.actuated.size(); ++j) {
    const ArmJointMoves mv = calc_arm_joint_moves(m, j);
    if (mv.target != mv.start) t = std::max(t, mv.t_start);
  }
  return t;
}

double calc_arm_exit_time(double t_out, double e_out, double t_next, double e_next, double band, double t0,
                          double t_end, double dwell) {
  const double f = (e_out - band) / (e_out - e_next);
  const double exit = t_out + f * (t_next - t_out);
  if (exit > t_end - dwell) return std::nan("");
  return std::max(0.0, exit - t0);
}

ArmToolRest calc_arm_tool_rest(const ArmSettleRule& r, std::span<const double> t, std::span<const double> x,
                               std::span<const double> y, std::span<const double> z, const Vec3& begin,
                               const Vec3& target, double largest) {
  // Settling and overshoot about where the tool comes to rest (its last sample, as stepinfo's yfinal):
  // a flexible arm's tool rests off the rigid target by its sag, which <tool>_final_error_m reports.
  const std::size_t n = t.size();
  const Vec3 goal(x[n - 1], y[n - 1], z[n - 1]);
  std::vector<double> err(n);
  double over = 0.0;
  const Vec3 dir = (target - begin).norm() > 0.0 ? Vec3((target - begin).normalized()) : Vec3::Zero();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec3 q(x[k], y[k], z[k]);
    err[k] = (q - goal).norm();
    if (t[k] >= r.t0) over = std::max(over, dir.dot(q - goal));
  }
  const double tool_band = r.tool_band > 0.0 ? r.tool_band : r.band * largest;
  return {largest > 0.0 ? last_exit(t, err, r.t0, tool_band, r.dwell) : 0.0,
          (target - begin).norm() > 0.0 ? 100.0 * over / (target - begin).norm() : 0.0};
}

std::vector<double> calc_arm_metrics(const ArmModel& m, const ArmTrace& tr, LaneStatus status) {
  const std::vector<std::string> cols = arm_metric_columns(m);
  std::vector<double> v(cols.size(), std::nan(""));
  if (status != LaneStatus::kOk) return v;
  const std::vector<double>& t = tr.t();
  const ArmSettleRule rule = make_arm_settle_rule(m);
  const double t0 = rule.t0;
  std::size_t c = 0;
  const std::size_t na = m.actuated.size();
  for (std::size_t j = 0; j < na; ++j) {
    const ActuatedJoint& a = m.actuated[j];
    const std::vector<double>& q = tr.column(a.name + ".q");
    // The joint's largest move and its last move (start, target).
    const ArmJointMoves mv = calc_arm_joint_moves(m, j);
    std::vector<double> e(q.size());
    for (std::size_t k = 0; k < q.size(); ++k) e[k] = std::abs(q[k] - mv.final_target);
    v[c++] = mv.largest > 0.0 ? last_exit(t, e, t0, rule.band * mv.largest, rule.dwell) : 0.0;
    // Over the last move's samples (none when the run ends before it starts: no number, as OnlineOvershoot).
    v[c++] = mv.target == mv.start ? 0.0
             : mv.t_start <= t.back() ? calc_overshoot(t, q, mv.t_start, MoveWindow{t0, t.back(), mv.start, mv.target})
                                      : std::nan("");
    v[c++] = peak_abs(tr.column(a.name + ".torque"));
    v[c++] = peak_abs(tr.column(a.name + ".qd"));
  }
  // Each tool: its final target, its largest and last moves in the rigid reference (the last from the
  // first sample at or after the arm's last move's start).
  const std::size_t n = t.size();
  const std::size_t last = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), calc_arm_last_move_start(m)) - t.begin());
  for (const ArmTool& tool : m.tools) {
    const std::string& p = tool.name;
    const std::vector<double>*x[3] = {&tr.column(p + ".x"), &tr.column(p + ".y"), &tr.column(p + ".z")};
    const std::vector<double>*xr[3] = {&tr.column(p + ".ref_x"), &tr.column(p + ".ref_y"), &tr.column(p + ".ref_z")};
    const Vec3 target((*xr[0])[n - 1], (*xr[1])[n - 1], (*xr[2])[n - 1]);
    const Vec3 begin((*xr[0])[0], (*xr[1])[0], (*xr[2])[0]);
    const Vec3 last_begin = last < n ? Vec3((*xr[0])[last], (*xr[1])[last], (*xr[2])[last]) : target;
    double largest = 0.0;
    for (std::size_t k = 0; k < n; ++k)
      largest = std::max(largest, (Vec3((*xr[0])[k], (*xr[1])[k], (*xr[2])[k]) - begin).norm());
    std::vector<double> track(n);
    for (std::size_t k = 0; k < n; ++k)
      track[k] = (Vec3((*x[0])[k], (*x[1])[k], (*x[2])[k]) - Vec3((*xr[0])[k], (*xr[1])[k], (*xr[2])[k])).norm();
    const ArmToolRest rest = calc_arm_tool_rest(rule, t, *x[0], *x[1], *x[2], last_begin, target, largest);
    v[c++] = rest.settling_s;
    v[c++] = rest.overshoot_pct;
    v[c++] = peak_abs(track);
    v[c++] = track[n - 1];
    v[c++] = track[0];
  }
  // The flexible links' tips.
  for (const LinkTip& l : m.links) {
    const std::vector<double>& dy = tr.column(l.name + ".deflection_y");
    const std::vector<double>& dz = tr.column(l.name + ".deflection_z");
    double peak = 0.0;
    for (std::size_t k = 0; k < n; ++k) peak = std::max(peak, std::hypot(dy[k], dz[k]));
    v[c++] = peak;
    const double t_end = t[n - 1];
    v[c++] = t0 < t_end ? std::max(calc_residual_amplitude(t, dy, t0, t_end), calc_residual_amplitude(t, dz, t0, t_end))
                        : std::nan("");
    v[c++] = std::hypot(dy[0], dz[0]);
  }
  if (m.collision.active()) {
    const std::size_t nc = m.collision.columns();
    std::vector<const std::vector<double>*> cols{&tr.column("clearance")};
    for (const std::string& p : m.collision.parts) cols.push_back(&tr.column(p + ".clearance"));
    for (const Obstacle& o : m.collision.world.obstacles) cols.push_back(&tr.column(o.name + ".clearance"));
    ClearanceMetrics cm(nc);
    std::vector<double> row(nc);
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t i = 0; i < nc; ++i) row[i] = (*cols[i])[k];
      cm.add(t[k], row.data(), 1);
    }
    cm.result(&v[c]);
    c += ClearanceMetrics::kLeading + nc - 1;
  }
  if (!m.monitors.empty()) {
    const std::size_t nm = m.monitors.size();
    std::vector<const std::vector<double>*> tripped;
    for (const ArmMonitor& o : m.monitors) tripped.push_back(&tr.column(o.name + ".tripped"));
    const std::string& p = m.tools.front().name;
    const std::vector<double>*x[3] = {&tr.column(p + ".x"), &tr.column(p + ".y"), &tr.column(p + ".z")};
    MonitorMetrics mm(m);
    std::vector<double> row(nm);
    double tool[3];
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t i = 0; i < nm; ++i) row[i] = (*tripped[i])[k];
      for (std::size_t i = 0; i < 3; ++i) tool[i] = (*x[i])[k];
      mm.add(t[k], row.data(), tool, 1);
    }
    mm.result(&v[c]);
    c += nm + MonitorMetrics::kTrailing;
  }
  v[c++] = std::max(0.0, t[n - 1] - t0 - rule.dwell);
  return v;
}

void ClearanceMetrics::add(double t, const double* c, std::size_t stride) {
  const double now = c[0];
  if (now < mins_[0]) t_min_ = t;
  for (std::size_t i = 0; i < mins_.size(); ++i) mins_[i] = std::min(mins_[i], c[i * stride]);
  // A contact begins where the clearance reaches 0 from above (or is there at the start).
  if (now <= 0.0 && (!started_ || c_prev_ > 0.0)) {
    ++contacts_;
    if (std::isnan(first_contact_))
      first_contact_ = started_ && std::isfinite(c_prev_) ? t_prev_ + (t - t_prev_) * c_prev_ / (c_prev_ - now) : t;
  }
  t_prev_ = t, c_prev_ = now, started_ = true;
}

void ClearanceMetrics::result(double* out) const {
  out[0] = mins_[0];
  out[1] = t_min_;
  out[2] = first_contact_;
  out[3] = static_cast<double>(contacts_);
  out[4] = contacts_ > 0 ? 1.0 : 0.0;
  for (std::size_t i = 1; i < mins_.size(); ++i) out[kLeading + i - 1] = mins_[i];
}

MonitorMetrics::MonitorMetrics(const ArmModel& m) : trip_t_(m.monitors.size(), std::nan("")) {
  for (const ArmMonitor& o : m.monitors) {
    actions_.push_back(o.action);
    delays_.push_back(o.delay_samples);
  }
}

void MonitorMetrics::Path::add(long k, double t, double step, double dt) {
  if (start < 0 || k < start) return;
  if (k == start) {
    started = true;
    t_start = t_moved = t;
    return;
  }
  distance += step;
  moving = step / dt >= kRestSpeed;
  if (moving) t_moved = t;
}

void MonitorMetrics::add(double t, const double* tripped, const double* tool, std::size_t stride) {
  // The trips at this sample (in monitor order: the lowest index first among those of one sample).
  for (std::size_t i = 0; i < trip_t_.size(); ++i) {
    if (!(tripped[i * stride] != 0.0) || !std::isnan(trip_t_[i])) continue;
    trip_t_[i] = t;
    if (first_ < 0) {
      first_ = static_cast<int>(i);
      from_first_.start = n_ + delays_[i];
    }
    if (acting_ < 0 && actions_[i] != MonitorAction::kRecord) {
      acting_ = static_cast<int>(i);
      from_acting_.start = n_ + delays_[i];
    }
  }
  const Vec3 x(tool[0], tool[stride], tool[2 * stride]);
  const double step = n_ > 0 ? (x - previous_).norm() : 0.0, dt = t - t_previous_;
  from_first_.add(n_, t, step, dt);
  from_acting_.add(n_, t, step, dt);
  previous_ = x;
  t_previous_ = t;
  ++n_;
}

void MonitorMetrics::result(double* out) const {
  const std::size_t nm = trip_t_.size();
  for (std::size_t i = 0; i < nm; ++i) out[i] = trip_t_[i];
  const Path& p = acting_ >= 0 ? from_acting_ : from_first_;
  out[nm] = first_ >= 0 ? trip_t_[static_cast<std::size_t>(first_)] : std::nan("");
  out[nm + 1] = static_cast<double>(first_ + 1);
  out[nm + 2] = p.started ? p.distance : std::nan("");
  out[nm + 3] = p.started && !p.moving ? p.t_moved - p.t_start : std::nan("");
}

std::string calc_arm_status(const ArmModel& m, LaneStatus lane, const std::vector<std::string>& columns,
                            const std::vector<double>& values) {
  if (lane != LaneStatus::kOk) return lane_status_name(lane);
  for (std::size_t i = 0; i < columns.size(); ++i)
    for (const ArmTool& t : m.tools)
      if (columns[i] == t.name + "_settling_s" && std::isnan(values[i])) return "not_settled";
  return "ok";
}

std::vector<std::string> arm_tool_names(const std::vector<std::string>& columns) {
  std::vector<std::string> out;
  for (const std::string& c : columns)
    if (c.ends_with("_peak_error_m")) out.push_back(c.substr(0, c.size() - std::string("_peak_error_m").size()));
  return out;
}

}  // namespace ff
