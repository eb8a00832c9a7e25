#include "kernel/batch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "kernel/drive.hpp"
#include "kernel/friction.hpp"
#include "kernel/notch.hpp"
#include "common/random.hpp"

namespace ff {

const char* lane_status_name(LaneStatus s) {
  switch (s) {
    case LaneStatus::kOk: return "ok";
    case LaneStatus::kNonfinite: return "nonfinite";
    case LaneStatus::kSolverFail: return "solver_fail";
  }
  return "?";
}

NotchDesign make_notch_design(const Model& m) {
  NotchDesign d;
  d.order = m.spec.notch.order;
  for (int i = 0; i < 2; ++i) {
    d.omega_z[i] = m.omega_z[i];
    d.alpha[i] = m.spec.notch.alpha[i];
    d.zeta[i] = m.spec.notch.zeta[i];
  }
  return d;
}

int calc_sensor_hold(const ChannelSpec& ch, double controller_rate) {
  return ch.rate > 0 ? static_cast<int>(std::lround(controller_rate / ch.rate)) : 1;
}

BatchShape batch_shape_of(const Model& m) {
  const auto& ss = m.spec.sensors;
  BatchShape b;
  b.nseg = m.nseg;
  b.notch_sections = m.spec.notch.enabled ? 2 * m.spec.notch.order + 1 : 0;
  b.substeps = m.substeps;
  b.control_period = m.control_period;
  b.duration = m.duration;
  b.integrator = m.spec.simulation.integrator;
  b.drive_parts = (m.spec.hydraulics.enabled ? 1 : 0) + (m.spec.drive.enabled ? 2 : 0) +
                  (m.spec.friction.model == "lugre" ? 4 : 0);
  b.recorded = (ss.strain_gauge.enabled ? 1 : 0) + (ss.tip_accelerometer.enabled ? 2 : 0) +
               (ss.tip_position.enabled ? 4 : 0);
  return b;
}

BatchModel make_batch(std::span<const Model> models) {
  if (models.empty()) throw std::invalid_argument("make_batch: no models");
  if (models.size() > static_cast<std::size_t>(kMaxLanes)) throw std::invalid_argument("make_batch: more than kMaxLanes lanes");
  const Model& m0 = models[0];
  BatchModel bm;
  bm.W = static_cast<int>(models.size());
  const BatchShape shape = batch_shape_of(m0);
  bm.nseg = shape.nseg;
  bm.nsections = shape.notch_sections;
  bm.substeps = shape.substeps;
  bm.control_period = shape.control_period;
  bm.duration = shape.duration;
  for (const auto& m : models)
    if (batch_shape_of(m) != shape)
      throw std::invalid_argument(
          "make_batch: models differ in shape (segments, notch order, rate, substeps, duration, integrator, hub "
          "drive parts or recorded sensors)");
  bm.layout = make_drive_layout(m0.spec);
  for (const auto& m : models) bm.drive.push_back(make_lane_drive(m));
  bm.models.assign(models.begin(), models.end());

  const int W = bm.W, N = bm.nseg;
  auto per_body = [&](auto get) {
    std::vector<double> x(static_cast<std::size_t>(N) * W);
    for (int l = 0; l < W; ++l)
      for (int i = 0; i < N; ++i) x[i * W + l] = get(models[l], i);
    return x;
  };
  bm.body_mass = per_body([](const Model& m, int i) { return m.body[i].mass; });
  bm.body_first = per_body([](const Model& m, int i) { return m.body[i].first; });
  bm.body_inertia = per_body([](const Model& m, int i) { return m.body[i].inertia; });
  bm.seg_length = per_body([](const Model& m, int i) { return m.seg_length[i]; });
  bm.joint_k = per_body([](const Model& m, int i) { return m.joint_k[i]; });
  bm.joint_c = per_body([](const Model& m, int i) { return m.joint_c[i]; });
  bm.joint_k3 = per_body([](const Model& m, int i) { return m.joint_k3[i]; });

  for (const auto& m : models) {
    const auto& c = m.spec.controller;
    bm.kp.push_back(c.kp);
    bm.ki.push_back(c.ki);
    bm.kd.push_back(c.kd);
    bm.torque_limit.push_back(c.torque_limit > 0 ? c.torque_limit : std::numeric_limits<double>::infinity());
    bm.load_comp.push_back(c.load_compensation);
    bm.load_pressure.push_back(c.load_signal == "pressure" ? 1 : 0);
    bm.ff_gain.push_back(c.feedforward);
  }

  for (const auto& m : models) {
    const auto& f = m.spec.friction;
    bm.friction.push_back(make_friction_map(f));
    bm.hub_offset.push_back(m.spec.hub_torque_offset);
  }
  for (const auto& m : models) {
    bm.expected_readings.push_back(m.spec.simulation.expected_readings ? 1 : 0);
    const ChannelSpec* ch[2] = {&m.spec.sensors.hub_angle, &m.spec.sensors.hub_rate};
    for (int c = 0; c < 2; ++c) {
      bm.sensor_resolution[c].push_back(ch[c]->resolution);
      bm.sensor_noise[c].push_back(ch[c]->noise);
      const int hold = calc_sensor_hold(*ch[c], m.spec.controller.rate);
      bm.sensor_delay[c].push_back(ch[c]->delay);
      bm.sensor_hold[c].push_back(hold);
      bm.sensor_key[c].push_back(calc_variant_seed(m.spec.simulation.seed, static_cast<std::uint64_t>(c)));
      bm.sensor_history = std::max(bm.sensor_history, ch[c]->delay + hold);
    }
  }
  for (const auto& m : models) {
    const SensorSpec& ss = m.spec.sensors;
    const RecordedChannelSpec* ch[kRecordedChannels] = {&ss.strain_gauge, &ss.tip_accelerometer, &ss.tip_position};
    for (int c = 0; c < kRecordedChannels; ++c) {
      bm.rec_enabled[c] = ch[c]->enabled;
      const int hold = calc_sensor_hold(*ch[c], m.spec.controller.rate);
      bm.rec_resolution[c].push_back(ch[c]->resolution);
      bm.rec_noise[c].push_back(ch[c]->noise);
      bm.rec_delay[c].push_back(ch[c]->delay);
      bm.rec_hold[c].push_back(hold);
      bm.rec_key[c].push_back(calc_variant_seed(m.spec.simulation.seed, static_cast<std::uint64_t>(2 + c)));
      if (ch[c]->enabled) bm.rec_history = std::max(bm.rec_history, ch[c]->delay + hold);
    }
    bm.strain_joint.push_back(ss.strain_gauge.joint);
    bm.strain_gain.push_back(calc_strain_tip_gain(m.spec.beam, m.nseg, ss.strain_gauge.joint));
    bm.notch_feedback.push_back(m.spec.notch.placement == "feedback" ? 1 : 0);
  }

  bm.notch_coef.assign(static_cast<std::size_t>(5) * bm.nsections * W, 0.0);
  if (bm.nsections > 0)
    for (int l = 0; l < W; ++l)
      pack_notch_sections(make_notch_sections(make_notch_design(models[l]), bm.control_period), W, l,
                          bm.notch_coef.data());
  return bm;
}

BodyTable make_body_table(const BatchModel& bm, const TipLoad& tip) {
  return {bm.W, bm.nseg, bm.body_mass.data(), bm.body_first.data(), bm.body_inertia.data(),
          {tip.mass.data(), tip.first.data(), tip.inertia.data()}};
}

BodyTable make_body_table(const BatchModel& bm) {
  const std::size_t o = static_cast<std::size_t>(bm.nseg - 1) * bm.W;
  return {bm.W, bm.nseg, bm.body_mass.data(), bm.body_first.data(), bm.body_inertia.data(),
          {bm.body_mass.data() + o, bm.body_first.data() + o, bm.body_inertia.data() + o}};
}

BatchState make_state(const BatchModel& bm) {
  BatchState s;
  const std::size_t nw = static_cast<std::size_t>(bm.nseg) * bm.W;
  s.q.assign(nw, 0.0);
  s.v.assign(nw, 0.0);
  s.a_prev.assign(nw, 0.0);
  s.z.assign(static_cast<std::size_t>(bm.layout.nz) * bm.W, 0.0);
  init_drive_state(bm, s.z.data());
  s.tau.assign(bm.W, 0.0);
  s.integral.assign(bm.W, 0.0);
  s.notch_state.assign(static_cast<std::size_t>(2) * bm.nsections * bm.W, 0.0);
  const std::size_t tip = static_cast<std::size_t>(bm.nseg - 1) * bm.W;
  s.tip.mass.assign(bm.body_mass.begin() + tip, bm.body_mass.begin() + tip + bm.W);
  s.tip.first.assign(bm.body_first.begin() + tip, bm.body_first.begin() + tip + bm.W);
  s.tip.inertia.assign(bm.body_inertia.begin() + tip, bm.body_inertia.begin() + tip + bm.W);
  s.status.assign(bm.W, LaneStatus::kOk);
  for (auto& m : s.measured) m.assign(static_cast<std::size_t>(bm.sensor_history) * bm.W, 0.0);
  for (int c = 0; c < kRecordedChannels; ++c)
    if (bm.rec_enabled[c]) s.recorded[c].assign(static_cast<std::size_t>(bm.rec_history) * bm.W, 0.0);
  return s;
}

void copy_lane(const BatchModel& bm, BatchState& s, int from, int to) {
  const int W = bm.W;
  // Every per-lane array is (rows x W), lane innermost.
  auto copy = [&](std::vector<double>& x) {
    for (std::size_t o = 0; o < x.size(); o += W) x[o + to] = x[o + from];
  };
  for (auto* x : {&s.q, &s.v, &s.a_prev, &s.z, &s.tau, &s.integral, &s.notch_state, &s.measured[0], &s.measured[1],
                  &s.tip.mass, &s.tip.first, &s.tip.inertia})
    copy(*x);
  for (auto& x : s.recorded) copy(x);
  s.status[to] = s.status[from];
}

Workspace make_workspace(const BatchModel& bm) {
  Workspace ws;
  const std::size_t nw = static_cast<std::size_t>(bm.nseg) * bm.W;
  for (auto* x : {&ws.cq, &ws.sq, &ws.vw, &ws.vx, &ws.vy, &ws.cy, &ws.cz, &ws.i00, &ws.i01, &ws.i02, &ws.i11,
                  &ws.i12, &ws.i22, &ws.p0, &ws.p1, &ws.p2, &ws.d, &ws.u, &ws.a0, &ws.a1, &ws.a2, &ws.armature,
                  &ws.q1, &ws.v1, &ws.tau_joint})
    x->assign(nw, 0.0);
  const std::size_t nzw = static_cast<std::size_t>(bm.layout.nz) * bm.W;
  for (int k = 0; k < 4; ++k) {
    ws.kq[k].assign(nw, 0.0);
    ws.kv[k].assign(nw, 0.0);
    ws.kz[k].assign(nzw, 0.0);
  }
  for (auto* x : {&ws.z1, &ws.zdot, &ws.zpert, &ws.znew}) x->assign(nzw, 0.0);
  ws.zjac.assign(nzw * bm.layout.nz, 0.0);
  ws.tau_hub.assign(bm.W, 0.0);
  return ws;
}

}  // namespace ff
