// Online arm metrics (arm_online_metrics.hpp; the stored form is arm_metrics.cpp's calc_arm_metrics).
#include "arm/arm_online_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "arm/arm_simulate.hpp"  // arm_trace_names

namespace ff {

namespace {

// The index of a trace column by its name.
std::size_t column_index(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw std::logic_error("OnlineArmRun: no trace column '" + name + "'");
  return static_cast<std::size_t>(it - names.begin());
}

}  // namespace

void ArmLastExit::add(double t, double e) {
  if (pending_) {
    t_next_ = t;
    e_next_ = e;
    pending_ = false;
  }
  if (t >= t0_ && e > band_) {
    out_ = pending_ = true;
    t_out_ = t;
    e_out_ = e;
  }
}

double ArmLastExit::result(double t_end, double dwell) const {
  if (!out_) return 0.0;
  if (pending_) return std::nan("");  // outside at the last sample: not settled
  return calc_arm_exit_time(t_out_, e_out_, t_next_, e_next_, band_, t0_, t_end, dwell);
}

OnlineArmRun::OnlineArmRun(const ArmModel& m)
    : rule_(make_arm_settle_rule(m)), last_move_start_(calc_arm_last_move_start(m)), ncolumns_(arm_metric_columns(m).size()) {
  const std::vector<std::string> names = arm_trace_names(m);
  for (std::size_t j = 0; j < m.actuated.size(); ++j) {
    const std::string& a = m.actuated[j].name;
    const ArmJointMoves mv = calc_arm_joint_moves(m, j);
    std::optional<OnlineOvershoot> over;
    if (mv.target != mv.start) over.emplace(mv.t_start, MoveWindow{rule_.t0, kInf, mv.start, mv.target});
    joints_.push_back({column_index(names, a + ".q"), column_index(names, a + ".qd"), column_index(names, a + ".torque"),
                       mv, ArmLastExit(rule_.t0, rule_.band * mv.largest), over});
  }
  // The tools' paths are kept whole: reserved for the run's samples.
  const std::size_t samples = static_cast<std::size_t>(calc_arm_samples(m));
  for (const ArmTool& tool : m.tools) {
    Tool t;
    t.x = column_index(names, tool.name + ".x");
    t.ref_x = column_index(names, tool.name + ".ref_x");
    for (std::vector<double>* p : {&t.x_path, &t.y_path, &t.z_path}) p->reserve(samples);
    tools_.push_back(std::move(t));
  }
  if (!m.tools.empty()) t_.reserve(samples);
  for (const LinkTip& l : m.links)
    links_.push_back({column_index(names, l.name + ".deflection_y"), column_index(names, l.name + ".deflection_z"),
                      OnlineResidual(rule_.t0, kInf), OnlineResidual(rule_.t0, kInf)});
  if (m.collision.active()) {
    clearance_column_ = column_index(names, "clearance");
    clearance_columns_ = m.collision.columns();
    clearance_.emplace(m.collision.columns());
  }
  if (!m.monitors.empty()) {
    monitor_column_ = column_index(names, m.monitors.front().name + ".tripped");
    monitor_tool_ = column_index(names, m.tools.front().name + ".x");
    monitors_.emplace(m);
    monitor_count_ = m.monitors.size();
  }
}

void OnlineArmRun::add(const double* row, std::size_t stride) {
  auto at = [&](std::size_t c) { return row[c * stride]; };
  const double t = at(0);
  // The joints: distance from the final target, overshoot past the last move's target, peaks.
  for (Joint& j : joints_) {
    const double q = at(j.q);
    j.settling.add(t, std::abs(q - j.moves.final_target));
    if (j.overshoot) j.overshoot->add(t, q);
    j.peak_torque.add(t, at(j.torque));
    j.peak_speed.add(t, at(j.qd));
  }
  // The tools: the reference's start and largest move, the tracking error, the path.
  for (Tool& tool : tools_) {
    const Vec3 x(at(tool.x), at(tool.x + 1), at(tool.x + 2));
    const Vec3 xr(at(tool.ref_x), at(tool.ref_x + 1), at(tool.ref_x + 2));
    if (n_ == 0) tool.begin = xr;
    if (!tool.last_started && t >= last_move_start_) tool.last_begin = xr, tool.last_started = true;
    tool.target = xr;
    tool.largest = std::max(tool.largest, (xr - tool.begin).norm());
    const double track = (x - xr).norm();
    tool.peak_error.add(t, track);
    tool.final_error = track;
    if (n_ == 0) tool.sag = track;
    tool.x_path.push_back(x.x());
    tool.y_path.push_back(x.y());
    tool.z_path.push_back(x.z());
  }
  if (!tools_.empty()) t_.push_back(t);
  // The links' tips.
  for (Link& l : links_) {
    const double dy = at(l.dy), dz = at(l.dz);
    l.peak.add(t, std::hypot(dy, dz));
    l.residual_y.add(t, dy);
    l.residual_z.add(t, dz);
    if (n_ == 0) l.sag = std::hypot(dy, dz);
  }
  if (clearance_) clearance_->add(t, row + clearance_column_ * stride, stride);
  if (monitors_) monitors_->add(t, row + monitor_column_ * stride, row + monitor_tool_ * stride, stride);
  t_last_ = t;
  ++n_;
}

std::vector<double> OnlineArmRun::result(LaneStatus status) const {
  std::vector<double> v(ncolumns_, std::nan(""));
  if (status != LaneStatus::kOk || n_ == 0) return v;
  const double t0 = rule_.t0;
  std::size_t c = 0;
  for (const Joint& j : joints_) {
    v[c++] = j.moves.largest > 0.0 ? j.settling.result(t_last_, rule_.dwell) : 0.0;
    v[c++] = j.overshoot ? j.overshoot->result() : 0.0;
    v[c++] = j.peak_torque.result();
    v[c++] = j.peak_speed.result();
  }
  for (const Tool& tool : tools_) {
    const ArmToolRest rest = calc_arm_tool_rest(rule_, t_, tool.x_path, tool.y_path, tool.z_path,
                                                tool.last_started ? tool.last_begin : tool.target, tool.target, tool.largest);
    v[c++] = rest.settling_s;
    v[c++] = rest.overshoot_pct;
    v[c++] = tool.peak_error.result();
    v[c++] = tool.final_error;
    v[c++] = tool.sag;
  }
  for (const Link& l : links_) {
    v[c++] = l.peak.result();
    v[c++] = t0 < t_last_ ? std::max(l.residual_y.result(), l.residual_z.result()) : std::nan("");
    v[c++] = l.sag;
  }
  if (clearance_) {
    clearance_->result(&v[c]);
    c += ClearanceMetrics::kLeading + clearance_columns_ - 1;
  }
  if (monitors_) {
    monitors_->result(&v[c]);
    c += monitor_count_ + MonitorMetrics::kTrailing;
  }
  v[c++] = std::max(0.0, t_last_ - t0 - rule_.dwell);
  return v;
}

}  // namespace ff
