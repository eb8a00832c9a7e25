// simulate_arms (arm_simulate.hpp): the sample loop over lanes.
#include "arm/arm_simulate.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "arm/arm_online_metrics.hpp"
#include "common/errors.hpp"
#include "common/files.hpp"
#include "common/text.hpp"
#include "kernel/sensors.hpp"
#include "multibody/lane_integrators.hpp"
#include "multibody/lanes.hpp"
#include "multibody/tree_cvode.hpp"

namespace ff {

const std::vector<double>& ArmTrace::column(const std::string& name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return columns[i];
  throw std::out_of_range("arm trace has no column '" + name + "'");
}

std::vector<std::string> arm_trace_names(const ArmModel& m) {
  std::vector<std::string> n{"t"};
  for (const ActuatedJoint& a : m.actuated)
    for (const char* s : {".ref", ".q", ".qd", ".torque"}) n.push_back(a.name + s);
  for (const ArmTool& t : m.tools)
    for (const char* s : {".x", ".y", ".z", ".ref_x", ".ref_y", ".ref_z"}) n.push_back(t.name + s);
  for (const LinkTip& l : m.links)
    for (const char* s : {".deflection_y", ".deflection_z"}) n.push_back(l.name + s);
  if (m.collision.active()) {
    n.push_back("clearance");
    for (const std::string& p : m.collision.parts) n.push_back(p + ".clearance");
    for (const Obstacle& o : m.collision.world.obstacles) n.push_back(o.name + ".clearance");
  }
  for (const ActuatedJoint& a : m.actuated)
    for (const char* s : {".q_measured", ".qd_measured"}) n.push_back(a.name + s);
  for (const ActuatedJoint& a : m.actuated)
    if (a.control.hydraulics.enabled)
      for (const char* s : {".pressure_a", ".pressure_b"}) n.push_back(a.name + s);
  for (const ArmMonitor& o : m.monitors) n.push_back(o.name + ".tripped");
  return n;
}

std::string explain_arm_shape_mismatch(const ArmModel& a, const ArmModel& b) {
  if (a.tree.num_bodies() != b.tree.num_bodies() || a.tree.nv() != b.tree.nv()) return "the trees differ in size";
  for (int i = 0; i < a.tree.num_bodies(); ++i)
    if (a.tree.body(i).parent != b.tree.body(i).parent || a.tree.body(i).joint != b.tree.body(i).joint)
      return "the trees differ at body " + std::to_string(i);
  if (a.actuated.size() != b.actuated.size()) return "the actuated joints differ";
  for (std::size_t j = 0; j < a.actuated.size(); ++j)
    if (a.actuated[j].dof != b.actuated[j].dof || a.actuated[j].notch.size() != b.actuated[j].notch.size() ||
        a.actuated[j].notch_on_feedback != b.actuated[j].notch_on_feedback ||
        a.actuated[j].control.hydraulics.enabled != b.actuated[j].control.hydraulics.enabled ||
        a.actuated[j].control.drive != b.actuated[j].control.drive ||
        (a.actuated[j].control.friction.model == "lugre") != (b.actuated[j].control.friction.model == "lugre"))
      return "joint " + a.actuated[j].name + "'s control differs in shape";
  if (a.links.size() != b.links.size()) return "the flexible links differ";
  if (a.collision.columns() != b.collision.columns() || a.collision.parts != b.collision.parts)
    return "the world or the collision shapes differ";
  if (a.tools.size() != b.tools.size()) return "the tools differ";
  for (std::size_t t = 0; t < a.tools.size(); ++t)
    if (a.tools[t].name != b.tools[t].name) return "the tools differ";
  if (a.monitors.size() != b.monitors.size()) return "the monitors differ";
  for (std::size_t i = 0; i < a.monitors.size(); ++i)
    if (a.monitors[i].name != b.monitors[i].name) return "the monitors differ";
  if (a.control_period != b.control_period || a.duration != b.duration || a.substeps != b.substeps ||
      a.integrator != b.integrator || a.spec.rtol != b.spec.rtol || a.spec.atol != b.spec.atol)
    return "the rate, duration, substeps, integrator or its tolerances differ";
  return "";
}

namespace {

using std::size_t;

// The lane's tool points and, per flexible link, its tip deflection in the root frame (out[3 t .. 3 t + 2]
// per tool t, then two per link), then the clearances (arm_collision.hpp, calc_arm_clearances).
void calc_plant_kinematics(const ArmModel& m, const Eigen::VectorXd& q, std::vector<Pose>& poses, double* out) {
  calc_body_poses(m.tree, q, poses);
  int k = 0;
  for (const ArmTool& t : m.tools) {
    const Vec3 tool = poses[static_cast<size_t>(t.body)].point(t.point);
    out[k++] = tool.x(), out[k++] = tool.y(), out[k++] = tool.z();
  }
  for (const LinkTip& l : m.links) {
    const Pose& root = poses[static_cast<size_t>(l.root_body)];
    const Vec3 tip = poses[static_cast<size_t>(l.tip_body)].point(l.tip_point);
    const Vec3 d = root.rotation.transpose() * (tip - root.position) - l.rigid_tip;
    out[k++] = d.y();
    out[k++] = d.z();
  }
  if (m.collision.active()) calc_arm_clearances(m.collision, poses, out + k);
}

// Where the rigid arm at the reference puts each tool point (calc_body_poses first).
Vec3 calc_reference_tool(const ArmTool& t, const std::vector<Pose>& poses) {
  return poses[static_cast<size_t>(t.body)].point(t.point);
}

// ---- The replay hook (ArmRunOptions::reference) ----
// The reference of every actuated joint at controller sample k from the samples, with central differences.
void eval_replay_reference(const std::vector<std::vector<double>>& ref, long k, double T, double* r, double* rd,
                           double* rdd) {
  for (size_t j = 0; j < ref.size(); ++j) {
    const std::vector<double>& x = ref[j];
    const long n = static_cast<long>(x.size());
    auto at = [&](long i) { return x[static_cast<size_t>(std::clamp(i, 0L, n - 1))]; };
    r[j] = at(k);
    rd[j] = (at(k + 1) - at(k - 1)) / (2.0 * T);
    rdd[j] = (at(k + 1) - 2.0 * at(k) + at(k - 1)) / (T * T);
  }
}

// The reference of every lane at sample k (its own trajectory and shapers, or the replay's samples).
void eval_lane_references(ArmLanes& a, long k) {
  const size_t na = static_cast<size_t>(a.na);
  for (int l = 0; l < a.W; ++l) {
    const size_t o = static_cast<size_t>(l) * na;
    if (a.reference)  // the replay hook
      eval_replay_reference(*a.reference, k, a.T, &a.r[o], &a.rd[o], &a.rdd[o]);
    else
      eval_arm_reference(a.models[static_cast<size_t>(l)], static_cast<double>(k) * a.T, &a.r[o], &a.rd[o], &a.rdd[o],
                         a.scratch.data());
  }
}

// Trace columns: t, 4 per actuated joint, the kinematics (6 per tool: its point and the reference's, then
// 2 per link, then the clearances), 2 measured per joint, 2 pressures per hydraulic joint, 1 per monitor.
size_t kinematics_column(const ArmLanes& a) { return 1 + 4 * static_cast<size_t>(a.na); }
size_t monitor_column(const ArmLanes& a) { return a.names.size() - static_cast<size_t>(a.nmon); }
size_t pressure_column(const ArmLanes& a) { return monitor_column(a) - 2 * static_cast<size_t>(a.nh); }
size_t measured_column(const ArmLanes& a) { return pressure_column(a) - 2 * static_cast<size_t>(a.na); }

// ---- The safety monitors (ArmModel::monitors) ----
// Whether monitor o of lane l trips at sample k, from the lane's outputs row (calc_arm_outputs's columns)
// before the control law.
bool eval_monitor(const ArmLanes& a, const ArmModel& m, const ArmMonitor& o, int l, long k) {
  const size_t W = static_cast<size_t>(a.W), kin0 = kinematics_column(a), nt = m.tools.size();
  auto at = [&](size_t c) { return a.row[c * W + static_cast<size_t>(l)]; };
  const size_t j = static_cast<size_t>(o.joint), tool = kin0 + 6 * static_cast<size_t>(o.tool);
  switch (o.type) {
    case MonitorType::kJointTorque:
      // The torque the joint gets now: an electric joint's held since the previous sample, a hydraulic
      // joint's its actuator's at this sample (in the row already).
      return std::abs(m.actuated[j].control.hydraulics.enabled ? at(4 + 4 * j) : a.tau_held[j * W + static_cast<size_t>(l)]) >
             o.limit;
    case MonitorType::kJointSpeed: return std::abs(at(3 + 4 * j)) > o.limit;
    case MonitorType::kDeflection: {
      const size_t c = kin0 + 6 * nt + 2 * static_cast<size_t>(o.link);
      return std::hypot(at(c), at(c + 1)) > o.limit;
    }
    case MonitorType::kToolSpeed: {
      if (k == 0) return false;
      const double* prev = &a.tool_prev[3 * static_cast<size_t>(o.tool) * W + static_cast<size_t>(l)];
      const Vec3 step(at(tool) - prev[0], at(tool + 1) - prev[W], at(tool + 2) - prev[2 * W]);
      return step.norm() / a.T > o.limit;
    }
    case MonitorType::kWorkspace:
      for (int i = 0; i < 3; ++i)
        if (at(tool + static_cast<size_t>(i)) < o.lower[i] || at(tool + static_cast<size_t>(i)) > o.upper[i]) return true;
      return false;
    case MonitorType::kClearance: return at(kin0 + 6 * nt + 2 * m.links.size()) < o.limit;
    case MonitorType::kCommand: return k >= o.command_sample;
  }
  return false;
}

// A joint's reference tau s into a controlled stop at deceleration `dec` from r0 moving at v0: r0 + v0 tau
// - dec sign(v0) tau^2 / 2 until its rate is zero, then held there (dec 0: a hold, r0 at once).
void eval_stop_reference(double r0, double v0, double dec, double tau, double& r, double& rd, double& rdd) {
  const double sign = (v0 > 0.0) - (v0 < 0.0);
  const double t_stop = dec > 0.0 ? std::abs(v0) / dec : 0.0;
  const double u = std::min(tau, t_stop);
  r = r0 + v0 * u - 0.5 * dec * sign * u * u;
  rd = tau < t_stop ? v0 - dec * sign * tau : 0.0;
  rdd = tau < t_stop ? -dec * sign : 0.0;
}

// Sample k of every lane's monitors: their trips from the row, the acting monitor and its start, the
// tools' points kept for the next sample; then a hold or stop in force replaces the lane's reference.
void update_arm_monitors(ArmLanes& a, long k) {
  const size_t W = static_cast<size_t>(a.W), na = static_cast<size_t>(a.na), kin0 = kinematics_column(a);
  for (int l = 0; l < a.W; ++l) {
    const size_t lu = static_cast<size_t>(l);
    const ArmModel& m = a.models[lu];
    for (size_t i = 0; i < m.monitors.size(); ++i) {
      const ArmMonitor& o = m.monitors[i];
      double& tripped = a.tripped[i * W + lu];
      if (tripped != 0.0 || !eval_monitor(a, m, o, l, k)) continue;
      tripped = 1.0;
      if (a.act_monitor[lu] < 0 && o.action != MonitorAction::kRecord) {
        a.act_monitor[lu] = static_cast<int>(i);
        a.act_sample[lu] = k + o.delay_samples;
      }
    }
    for (size_t c = 0; c < 3 * m.tools.size(); ++c)
      a.tool_prev[c * W + lu] = a.row[(kin0 + 6 * (c / 3) + c % 3) * W + lu];
    if (a.act_monitor[lu] < 0 || k < a.act_sample[lu]) continue;
    const ArmMonitor& o = m.monitors[static_cast<size_t>(a.act_monitor[lu])];
    if (o.action != MonitorAction::kHold && o.action != MonitorAction::kStop) continue;
    double *r = &a.r[lu * na], *rd = &a.rd[lu * na], *rdd = &a.rdd[lu * na];
    const double tau = static_cast<double>(k - a.act_sample[lu]) * a.T;
    for (size_t j = 0; j < na; ++j) {
      if (k == a.act_sample[lu]) a.act_r0[j * W + lu] = r[j], a.act_v0[j * W + lu] = rd[j];
      eval_stop_reference(a.act_r0[j * W + lu], a.act_v0[j * W + lu], o.action == MonitorAction::kStop ? o.deceleration : 0.0,
                          tau, r[j], rd[j], rdd[j]);
    }
  }
}

// The brake of lane l's acting monitor on the control law from its start on (nullptr when none).
const ArmMonitor* active_brake(const ArmLanes& a, int l, long k) {
  const int i = a.act_monitor[static_cast<size_t>(l)];
  if (i < 0 || k < a.act_sample[static_cast<size_t>(l)]) return nullptr;
  const ArmMonitor& o = a.models[static_cast<size_t>(l)].monitors[static_cast<size_t>(i)];
  return o.action == MonitorAction::kBrake ? &o : nullptr;
}

}  // namespace

long calc_arm_samples(const ArmModel& m) {
  return static_cast<long>(std::floor(m.duration / m.control_period + 1e-9)) + 1;
}

ArmLanes make_arm_lanes(std::span<const ArmModel> lanes, const ArmRunOptions& options) {
  if (lanes.empty()) throw std::invalid_argument("simulate_arms: no lanes");
  const ArmModel& m0 = lanes[0];
  for (size_t l = 1; l < lanes.size(); ++l)
    if (const std::string why = explain_arm_shape_mismatch(m0, lanes[l]); !why.empty())
      throw std::invalid_argument("simulate_arms: lane " + std::to_string(l) + ": " + why);
  ArmLanes a;
  a.models = lanes;
  a.reference = options.reference;
  const int W = a.W = static_cast<int>(lanes.size());
  const int na = a.na = static_cast<int>(m0.actuated.size());
  if (options.reference) {  // the replay hook
    bool ok = options.reference->size() == static_cast<size_t>(na);
    for (const std::vector<double>& x : *options.reference) ok &= !x.empty();
    if (!ok) throw std::invalid_argument("simulate_arms: the reference needs one non-empty sample vector per actuated joint");
  }
  const int nv = a.nv = m0.tree.nv();
  std::vector<Tree> trees;
  for (const ArmModel& m : lanes) trees.push_back(m.tree);
  a.tl = make_tree_lanes(trees);
  TreeLanes& tl = a.tl;
  // Each actuated joint's friction, in the plant (every integrator stage, CVODE's right-hand side): the
  // static map, or LuGre's bristles (a state each, after the actuators'); and a drive train's nonlinear
  // law at its twist, in every lane when one lane's drive there is nonlinear.
  for (int j = 0; j < na; ++j) {
    const ActuatedJoint& a0 = m0.actuated[static_cast<std::size_t>(j)];
    std::vector<FrictionSpec> f;
    std::vector<LaneDrive> law;
    bool nonlinear = false;
    for (const ArmModel& m : lanes) {
      const JointControlSpec& c = m.actuated[static_cast<std::size_t>(j)].control;
      f.push_back(c.friction);
      LaneDrive p;
      p.k = c.train.stiffness;
      p.k3 = c.train.cubic_stiffness;
      p.c = c.train.damping;
      p.b = 0.5 * c.train.backlash;
      p.closing = c.train.closing_damping;
      p.eta = c.train.efficiency;
      law.push_back(p);
      nonlinear = nonlinear || (c.drive && is_nonlinear_drive(c.train));
    }
    if (a0.control.friction.model == "lugre") add_tree_lanes_lugre(tl, a0.dof, f);
    else set_tree_lanes_friction(tl, a0.dof, f);
    if (nonlinear) add_tree_lanes_transmission(tl, m0.spec.tree.dof_index.at(a0.name + ".twist"), a0.dof, law);
  }
  // Each hydraulic joint's actuator (its states after the tree's, in joint order), its torque offset the
  // constant load on the joint; the chambers holding the joint's static load, the spool centred.
  for (int j = 0; j < na; ++j) {
    const ActuatedJoint& a0 = m0.actuated[static_cast<size_t>(j)];
    if (!a0.control.hydraulics.enabled) continue;
    std::vector<LaneDrive> p;
    std::vector<double> load;
    for (const ArmModel& m : lanes) {
      const ActuatedJoint& aj = m.actuated[static_cast<size_t>(j)];
      p.push_back(make_hydraulic_drive(aj.control.hydraulics));
      load.push_back(aj.control.torque_offset);
    }
    add_tree_lanes_hydraulics(tl, a0.dof, p, load);
    a.hyd_joints.push_back(j);
  }
  const int nh = a.nh = static_cast<int>(a.hyd_joints.size());
  a.s = make_tree_lanes_state(tl);
  TreeLanesState& s = a.s;
  for (int h = 0; h < nh; ++h)
    for (int l = 0; l < W; ++l) {
      const auto [pa, pb] = calc_initial_pressures(lanes[l].actuated[static_cast<size_t>(a.hyd_joints[static_cast<size_t>(h)])]);
      s.z[static_cast<size_t>((kHydraulicStates * h + 2) * W + l)] = pa / kPressureUnit;
      s.z[static_cast<size_t>((kHydraulicStates * h + 3) * W + l)] = pb / kPressureUnit;
    }
  a.z0 = s.z;
  a.ws = TreeStepWorkspace(tl);
  for (int l = 0; l < W; ++l)
    for (int j = 0; j < nv; ++j) {
      s.q[static_cast<size_t>(j * W + l)] = lanes[l].q0[j];
      s.qd[static_cast<size_t>(j * W + l)] = lanes[l].qd0.size() == nv ? lanes[l].qd0[j] : 0.0;
    }

  a.T = m0.control_period;
  // The variable-step reference: CVODE per lane over each control period.
  a.cvode_ok.assign(static_cast<size_t>(W), 1);
  if (m0.integrator == Integrator::kCvodeDense || m0.integrator == Integrator::kCvodeKlu ||
      m0.integrator == Integrator::kCvodeGmres) {
    TreeCvodeOptions o;
    o.solver = m0.integrator == Integrator::kCvodeDense ? TreeCvodeSolver::kDense
               : m0.integrator == Integrator::kCvodeKlu ? TreeCvodeSolver::kKlu
                                                        : TreeCvodeSolver::kGmres;
    o.rtol = m0.spec.rtol;
    o.atol = m0.spec.atol;
    a.cvode = std::make_unique<TreeCvode>(tl, o);
  }
  a.samples = calc_arm_samples(m0);
  a.names = arm_trace_names(m0);
  a.status.assign(static_cast<size_t>(W), LaneStatus::kOk);
  a.row.assign(a.names.size() * static_cast<size_t>(W), 0.0);

  // Controller state; each notch at rest at its first input.
  a.integral.assign(static_cast<size_t>(na * W), 0.0);
  a.tau_held.assign(static_cast<size_t>(na * W), 0.0);
  a.notch_coef.resize(static_cast<size_t>(na));
  a.notch_state.resize(static_cast<size_t>(na));
  a.notch_in.assign(static_cast<size_t>(W), 0.0);
  a.notch_out.assign(static_cast<size_t>(W), 0.0);
  a.r.assign(static_cast<size_t>(na * W), 0.0);
  a.rd = a.rdd = a.r;
  a.scratch.assign(3 * static_cast<size_t>(na), 0.0);
  a.tau_id.assign(static_cast<size_t>(na), 0.0);
  a.tau_g = a.tau_id;
  eval_lane_references(a, 0);
  for (int j = 0; j < na; ++j) {
    const int ns = static_cast<int>(m0.actuated[static_cast<size_t>(j)].notch.size());
    a.notch_coef[static_cast<size_t>(j)].assign(static_cast<size_t>(5 * ns * W), 0.0);
    a.notch_state[static_cast<size_t>(j)].assign(static_cast<size_t>(2 * ns * W), 0.0);
    for (int l = 0; l < W; ++l) {
      const ActuatedJoint& aj = lanes[l].actuated[static_cast<size_t>(j)];
      if (ns == 0) continue;
      pack_notch_sections(aj.notch, W, l, a.notch_coef[static_cast<size_t>(j)].data());
      const double x0 = aj.notch_on_feedback ? lanes[l].q0[aj.dof] : a.r[static_cast<size_t>(l * na + j)];
      reset_notch_state(ns, W, l, a.notch_coef[static_cast<size_t>(j)].data(), x0, a.notch_state[static_cast<size_t>(j)].data());
    }
  }

  for (const ArmModel& m : lanes) a.ff.emplace_back(arm_controller_model(m).tree);  // the controller's rigid arm
  a.poses.resize(static_cast<size_t>(m0.tree.num_bodies()));
  a.q_lane.resize(nv);
  a.q_ref.resize(nv);
  a.tau_applied.assign(static_cast<size_t>(nv * W), 0.0);
  a.kin.assign(a.names.size(), 0.0);
  a.e.assign(static_cast<size_t>(na * W), 0.0);  // the control errors
  // The sensors: what each joint's controller measures (joint j, lane l at [j * W + l]), and per joint
  // and channel a ring of past readings (H x W), H the longest delay + hold of any joint and lane.
  for (const ArmModel& m : lanes)
    for (const ActuatedJoint& aj : m.actuated)
      a.H = std::max({a.H, aj.control.angle_sensor.delay + aj.angle_hold, aj.control.rate_sensor.delay + aj.rate_hold});
  a.q_meas.assign(static_cast<size_t>(na * W), 0.0);
  a.qd_meas = a.q_meas;
  a.ring_q.assign(static_cast<size_t>(na), std::vector<double>(static_cast<size_t>(a.H * W), 0.0));
  a.ring_qd = a.ring_q;
  // The monitors: none tripped, none acting.
  a.nmon = static_cast<int>(m0.monitors.size());
  a.tripped.assign(static_cast<size_t>(a.nmon * W), 0.0);
  a.tool_prev.assign(3 * m0.tools.size() * static_cast<size_t>(W), 0.0);
  a.act_monitor.assign(static_cast<size_t>(W), -1);
  a.act_sample.assign(static_cast<size_t>(W), 0);
  a.act_r0.assign(static_cast<size_t>(na * W), 0.0);
  a.act_v0 = a.act_r0;
  return a;
}

void calc_arm_outputs(ArmLanes& a) {
  const int W = a.W, na = a.na, nv = a.nv;
  const size_t kin0 = kinematics_column(a), hyd0 = pressure_column(a);
  double* row = a.row.data();
  auto put = [&](size_t c, int l, double v) { row[c * static_cast<size_t>(W) + static_cast<size_t>(l)] = v; };
  for (int l = 0; l < W; ++l) {
    const ArmModel& m = a.models[static_cast<size_t>(l)];
    for (int j = 0; j < na; ++j) {
      const ActuatedJoint& aj = m.actuated[static_cast<size_t>(j)];
      put(static_cast<size_t>(2 + 4 * j), l, a.s.q[static_cast<size_t>(aj.dof * W + l)]);
      put(static_cast<size_t>(3 + 4 * j), l, a.s.qd[static_cast<size_t>(aj.dof * W + l)]);
    }
    // A hydraulic joint's torque is its actuator's, D (p_a - p_b), and its chamber pressures (Pa).
    for (int h = 0; h < a.nh; ++h) {
      const size_t z = static_cast<size_t>(kHydraulicStates * h * W + l);
      const size_t col = hyd0 + 2 * static_cast<size_t>(h);
      put(static_cast<size_t>(4 + 4 * a.hyd_joints[static_cast<size_t>(h)]), l,
          eval_hydraulic_actuator(a.tl.hydraulics[static_cast<size_t>(h * W + l)], 0.0, 0.0, 0.0, a.s.z.data() + z,
                                  static_cast<size_t>(W), nullptr));
      put(col, l, a.s.z[z + 2 * static_cast<size_t>(W)] * kPressureUnit);
      put(col + 1, l, a.s.z[z + 3 * static_cast<size_t>(W)] * kPressureUnit);
    }
    // The tools (<tool>.x/y/z, each before its reference's three columns) and the links' deflections.
    const size_t nt = m.tools.size(), n_plant = 3 * nt + 2 * m.links.size() + m.collision.columns();
    if (a.status[static_cast<size_t>(l)] == LaneStatus::kOk) {
      for (int j = 0; j < nv; ++j) a.q_lane[j] = a.s.q[static_cast<size_t>(j * W + l)];
      calc_plant_kinematics(m, a.q_lane, a.poses, a.kin.data());
    } else {
      std::fill(a.kin.begin(), a.kin.begin() + static_cast<std::ptrdiff_t>(n_plant), std::nan(""));
    }
    for (size_t t = 0; t < nt; ++t)
      for (size_t i = 0; i < 3; ++i) put(kin0 + 6 * t + i, l, a.kin[3 * t + i]);
    for (size_t i = 3 * nt; i < n_plant; ++i) put(kin0 + 3 * nt + i, l, a.kin[i]);
  }
}

void step_arm_controllers(ArmLanes& a, long k) {
  const int W = a.W, na = a.na;
  const std::span<const ArmModel> lanes = a.models;
  const ArmModel& m0 = lanes[0];
  const double T = a.T, t = static_cast<double>(k) * T;
  TreeLanesState& s = a.s;
  // What the sensors give the controllers now.
  for (int j = 0; j < na; ++j) {
    const int d = m0.actuated[static_cast<size_t>(j)].dof;
    for (int l = 0; l < W; ++l) {
      const ActuatedJoint& aj = lanes[l].actuated[static_cast<size_t>(j)];
      const ChannelSpec &ca = aj.control.angle_sensor, &cr = aj.control.rate_sensor;
      const size_t jl = static_cast<size_t>(j * W + l), dl = static_cast<size_t>(d * W + l);
      const bool expected = lanes[l].spec.expected_readings;
      a.q_meas[jl] = sample_channel(s.q[dl], ca.noise, expected, aj.angle_key, ca.resolution, ca.delay, aj.angle_hold, k,
                                    a.H, W, l, a.ring_q[static_cast<size_t>(j)].data());
      // A slipped encoder, from the first sample at or after its fault time.
      if (static_cast<double>(k) >= aj.control.angle_fault_time / T - 1e-9) a.q_meas[jl] += aj.control.angle_fault_offset;
      a.qd_meas[jl] = sample_channel(s.qd[dl], cr.noise, expected, aj.rate_key, cr.resolution, cr.delay, aj.rate_hold, k,
                                     a.H, W, l, a.ring_qd[static_cast<size_t>(j)].data());
    }
  }
  // The outputs that are the plant's (the monitors watch them), the reference of every lane (its own
  // trajectory and shapers), and the monitors: their trips, and a hold or stop in force on the reference.
  calc_arm_outputs(a);
  eval_lane_references(a, k);
  update_arm_monitors(a, k);
  // The notch on each joint's reference or feedback, all lanes at once.
  for (int j = 0; j < na; ++j) {
    const ActuatedJoint& a0 = m0.actuated[static_cast<size_t>(j)];
    const int ns = static_cast<int>(a0.notch.size());
    for (int l = 0; l < W; ++l) {
      const double q = a.q_meas[static_cast<size_t>(j * W + l)];
      a.notch_in[static_cast<size_t>(l)] = a0.notch_on_feedback ? q : a.r[static_cast<size_t>(l * na + j)];
    }
    if (ns > 0)
      step_notch(ns, W, a.notch_coef[static_cast<size_t>(j)].data(), a.notch_state[static_cast<size_t>(j)].data(),
                 a.notch_in.data(), a.notch_out.data());
    else std::copy(a.notch_in.begin(), a.notch_in.end(), a.notch_out.begin());
    for (int l = 0; l < W; ++l) {
      const double q = a.q_meas[static_cast<size_t>(j * W + l)];
      const double ref = a.r[static_cast<size_t>(l * na + j)];
      a.e[static_cast<size_t>(j * W + l)] =
          a0.notch_on_feedback ? ref - a.notch_out[static_cast<size_t>(l)] : a.notch_out[static_cast<size_t>(l)] - q;
    }
  }
  const size_t kin0 = kinematics_column(a), meas0 = measured_column(a), mon0 = monitor_column(a);
  double* row = a.row.data();
  auto put = [&](size_t c, int l, double v) { row[c * static_cast<size_t>(W) + static_cast<size_t>(l)] = v; };
  for (int l = 0; l < W; ++l) {
    const ArmModel& m = lanes[l];
    double* rl = &a.r[static_cast<size_t>(l * na)];
    double* rdl = &a.rd[static_cast<size_t>(l * na)];
    bool need_ff = false;
    for (const ActuatedJoint& aj : m.actuated) need_ff |= aj.control.feedforward != 0.0 || aj.control.gravity_compensation != 0.0;
    // The feed-forward and gravity compensation from the controller's model of the arm (the nominal one).
    if (need_ff)
      calc_arm_feedforward(arm_controller_model(m), rl, rdl, &a.rdd[static_cast<size_t>(l * na)], a.tau_id.data(), a.tau_g.data(),
                           a.ff[static_cast<size_t>(l)]);
    // PID with clamping anti-windup, saturation, feed-forward; or a monitor's brake, the integral frozen.
    const ArmMonitor* brake = active_brake(a, l, k);
    for (int j = 0; j < na; ++j) {
      const ActuatedJoint& aj = m.actuated[static_cast<size_t>(j)];
      const size_t jl = static_cast<size_t>(j * W + l);
      if (brake) {
        const double limit = brake->brake_torque > 0.0 ? brake->brake_torque : aj.torque_limit;
        a.tau_held[jl] = std::clamp(-m.brake_gain[static_cast<size_t>(j)] * s.qd[static_cast<size_t>(aj.dof * W + l)], -limit, limit);
        continue;
      }
      const double qd = a.qd_meas[jl];
      const double err = a.e[jl];
      double u = aj.control.kp * err + aj.control.ki * a.integral[jl] - aj.control.kd * qd;
      if (need_ff)
        u += aj.control.feedforward * (a.tau_id[static_cast<size_t>(j)] - a.tau_g[static_cast<size_t>(j)] + aj.control.kd * rdl[j]) +
             aj.control.gravity_compensation * a.tau_g[static_cast<size_t>(j)];
      double tau = u;
      bool saturated = false;
      if (aj.torque_limit > 0.0 && std::abs(u) > aj.torque_limit) {
        tau = std::copysign(aj.torque_limit, u);
        saturated = true;
      }
      if (!(saturated && err * u > 0.0)) a.integral[jl] += T * err;
      a.tau_held[jl] = tau;
    }
    // The outputs at this sample that are the controller's: the time, each joint's reference and
    // torque (a hydraulic joint's is its actuator's, the plant's), the reference's tool point, the
    // measurements, the monitors' trips.
    put(0, l, t);
    for (int j = 0; j < na; ++j) {
      put(static_cast<size_t>(1 + 4 * j), l, rl[j]);
      if (!m.actuated[static_cast<size_t>(j)].control.hydraulics.enabled)
        put(static_cast<size_t>(4 + 4 * j), l, a.tau_held[static_cast<size_t>(j * W + l)]);
    }
    for (int i = 0; i < a.nmon; ++i) put(mon0 + static_cast<size_t>(i), l, a.tripped[static_cast<size_t>(i * W + l)]);
    if (a.status[static_cast<size_t>(l)] == LaneStatus::kOk) {
      a.q_ref.setZero();
      for (int j = 0; j < na; ++j) a.q_ref[m.actuated[static_cast<size_t>(j)].dof] = rl[j];
      calc_body_poses(m.tree, a.q_ref, a.poses);
      for (size_t t = 0; t < m.tools.size(); ++t) {
        const Vec3 ref = calc_reference_tool(m.tools[t], a.poses);
        put(kin0 + 6 * t + 3, l, ref.x()), put(kin0 + 6 * t + 4, l, ref.y()), put(kin0 + 6 * t + 5, l, ref.z());
      }
    } else {
      for (size_t t = 0; t < m.tools.size(); ++t)
        for (size_t i = 3; i < 6; ++i) put(kin0 + 6 * t + i, l, std::nan(""));
    }
    for (int j = 0; j < na; ++j) {
      put(meas0 + 2 * static_cast<size_t>(j), l, a.q_meas[static_cast<size_t>(j * W + l)]);
      put(meas0 + 2 * static_cast<size_t>(j) + 1, l, a.qd_meas[static_cast<size_t>(j * W + l)]);
    }
  }
}

void step_arm_plant(ArmLanes& a, long k) {
  const int W = a.W, na = a.na, nv = a.nv;
  const ArmModel& m0 = a.models[0];
  const double T = a.T, t = static_cast<double>(k) * T, h = T / m0.substeps;
  TreeLanes& tl = a.tl;
  TreeLanesState& s = a.s;
  // The plant over one period with the torques held, less each joint's constant load; a hydraulic
  // joint's held torque is its valve loop's command (the load is the actuator's, TreeLanes).
  for (int j = 0; j < na; ++j) {
    const ActuatedJoint& a0 = m0.actuated[static_cast<size_t>(j)];
    const bool hydraulic = a0.control.hydraulics.enabled;
    for (int l = 0; l < W; ++l)
      a.tau_applied[static_cast<size_t>(a0.dof * W + l)] =
          a.tau_held[static_cast<size_t>(j * W + l)] -
          (hydraulic ? 0.0 : a.models[static_cast<size_t>(l)].actuated[static_cast<size_t>(j)].control.torque_offset);
  }
  if (a.cvode) {
    a.cvode->advance(tl, a.tau_applied.data(), s, t, T, a.cvode_ok);
    for (int l = 0; l < W; ++l)
      if (!a.cvode_ok[static_cast<size_t>(l)] && a.status[static_cast<size_t>(l)] == LaneStatus::kOk) {
        a.status[static_cast<size_t>(l)] = LaneStatus::kSolverFail;
        for (int j = 0; j < nv; ++j) s.q[static_cast<size_t>(j * W + l)] = std::nan("");
      }
  }
  for (int sub = 0; sub < (a.cvode ? 0 : m0.substeps); ++sub) {
    switch (m0.integrator) {
      case Integrator::kSdirk2: step_tree_sdirk2(tl, a.tau_applied.data(), s, a.ws, h); break;
      case Integrator::kMidpoint: step_tree_midpoint(tl, a.tau_applied.data(), s, a.ws, h); break;
      default: step_tree_rk4(tl, a.tau_applied.data(), s, a.ws, h); break;
    }
  }
  // A lane gone non-finite (or whose solver failed) is frozen at zero (its neighbours never see it:
  // lanes are independent).
  for (int l = 0; l < W; ++l) {
    if (a.status[static_cast<size_t>(l)] == LaneStatus::kNonfinite) continue;
    bool finite = true;
    for (int j = 0; j < nv; ++j)
      finite &= std::isfinite(s.q[static_cast<size_t>(j * W + l)]) && std::isfinite(s.qd[static_cast<size_t>(j * W + l)]);
    for (int i = 0; i < tl.nz(); ++i) finite &= std::isfinite(s.z[static_cast<size_t>(i * W + l)]);
    if (!finite) {
      if (a.status[static_cast<size_t>(l)] == LaneStatus::kOk) a.status[static_cast<size_t>(l)] = LaneStatus::kNonfinite;
      for (int j = 0; j < nv; ++j) {
        s.q[static_cast<size_t>(j * W + l)] = 0.0;
        s.qd[static_cast<size_t>(j * W + l)] = 0.0;
        s.a_prev[static_cast<size_t>(j * W + l)] = 0.0;
      }
      for (int i = 0; i < tl.nz(); ++i) s.z[static_cast<size_t>(i * W + l)] = a.z0[static_cast<size_t>(i * W + l)];
    }
  }
}

int calc_arm_state_size(const ArmLanes& a) { return 2 * a.nv + a.tl.nz(); }

void get_arm_state(const ArmLanes& a, int l, double* x) {
  const int W = a.W, nv = a.nv;
  for (int i = 0; i < nv; ++i) {
    x[i] = a.s.q[static_cast<size_t>(i * W + l)];
    x[nv + i] = a.s.qd[static_cast<size_t>(i * W + l)];
  }
  for (int i = 0; i < a.tl.nz(); ++i) x[2 * nv + i] = a.s.z[static_cast<size_t>(i * W + l)];
}

void set_arm_state(ArmLanes& a, int l, const double* x) {
  const int W = a.W, nv = a.nv;
  for (int i = 0; i < nv; ++i) {
    a.s.q[static_cast<size_t>(i * W + l)] = x[i];
    a.s.qd[static_cast<size_t>(i * W + l)] = x[nv + i];
  }
  for (int i = 0; i < a.tl.nz(); ++i) a.s.z[static_cast<size_t>(i * W + l)] = x[2 * nv + i];
}

void copy_arm_lane(const ArmLanes& a, int from, ArmLanes& b, int to) {
  if (a.nv != b.nv || a.na != b.na || a.tl.nz() != b.tl.nz() || a.H != b.H || a.notch_state.size() != b.notch_state.size() ||
      a.nmon != b.nmon || a.tool_prev.size() / static_cast<size_t>(a.W) != b.tool_prev.size() / static_cast<size_t>(b.W))
    throw std::invalid_argument("copy_arm_lane: lanes of another shape");
  // Row i of a (rows x a.W) array into row i of b's (rows x b.W).
  auto rows = [&](const std::vector<double>& x, std::vector<double>& y, size_t n) {
    for (size_t i = 0; i < n; ++i)
      y[i * static_cast<size_t>(b.W) + static_cast<size_t>(to)] = x[i * static_cast<size_t>(a.W) + static_cast<size_t>(from)];
  };
  const size_t nv = static_cast<size_t>(a.nv), na = static_cast<size_t>(a.na);
  rows(a.s.q, b.s.q, nv);
  rows(a.s.qd, b.s.qd, nv);
  rows(a.s.a_prev, b.s.a_prev, nv);
  rows(a.s.z, b.s.z, static_cast<size_t>(a.tl.nz()));
  rows(a.integral, b.integral, na);
  rows(a.tau_held, b.tau_held, na);
  rows(a.tripped, b.tripped, static_cast<size_t>(a.nmon));
  rows(a.tool_prev, b.tool_prev, a.tool_prev.size() / static_cast<size_t>(a.W));
  rows(a.act_r0, b.act_r0, na);
  rows(a.act_v0, b.act_v0, na);
  b.act_monitor[static_cast<size_t>(to)] = a.act_monitor[static_cast<size_t>(from)];
  b.act_sample[static_cast<size_t>(to)] = a.act_sample[static_cast<size_t>(from)];
  for (size_t j = 0; j < na; ++j) {
    if (a.notch_state[j].size() / static_cast<size_t>(a.W) != b.notch_state[j].size() / static_cast<size_t>(b.W))
      throw std::invalid_argument("copy_arm_lane: notches of another shape");
    rows(a.notch_state[j], b.notch_state[j], a.notch_state[j].size() / static_cast<size_t>(a.W));
    rows(a.ring_q[j], b.ring_q[j], static_cast<size_t>(a.H));
    rows(a.ring_qd[j], b.ring_qd[j], static_cast<size_t>(a.H));
  }
  b.status[static_cast<size_t>(to)] = a.status[static_cast<size_t>(from)];
}

ArmTrace make_arm_trace(const ArmLanes& a) {
  ArmTrace tr;
  tr.names = a.names;
  tr.columns.assign(a.names.size(), std::vector<double>(static_cast<size_t>(a.samples), 0.0));
  return tr;
}

void store_arm_row(const ArmLanes& a, int l, long k, ArmTrace& tr) {
  for (size_t c = 0; c < a.names.size(); ++c)
    tr.columns[c][static_cast<size_t>(k)] = a.row[c * static_cast<size_t>(a.W) + static_cast<size_t>(l)];
}

void mark_arm_trace_failure(const ArmLanes& a, ArmTrace& tr) {
  // The kinematic columns go NaN at the sample the lane failed at.
  const std::vector<double>& x = tr.columns[kinematics_column(a)];
  size_t first = 0;
  while (first < x.size() && std::isfinite(x[first])) ++first;
  for (size_t c = 1; c < tr.columns.size(); ++c)
    for (size_t k = first; k < tr.columns[c].size(); ++k) tr.columns[c][k] = std::nan("");
}

ArmRun simulate_arms(std::span<const ArmModel> lanes, const ArmRunOptions& options) {
  if (options.online && options.online->size() != lanes.size())
    throw std::invalid_argument("simulate_arms: one OnlineArmRun per lane expected");
  ArmLanes a = make_arm_lanes(lanes, options);
  const int W = a.W, nv = a.nv;
  const long samples = a.samples;
  ArmRun run;
  if (!options.online) run.traces.assign(static_cast<size_t>(W), make_arm_trace(a));
  if (options.keep_q) run.q.assign(static_cast<size_t>(W), Eigen::MatrixXd::Zero(nv, samples));
  for (long k = 0; k < samples; ++k) {
    step_arm_controllers(a, k);
    // The trace at this sample, or the lanes' online metrics.
    for (int l = 0; l < W; ++l) {
      if (options.online) (*options.online)[static_cast<size_t>(l)].add(a.row.data() + l, static_cast<size_t>(W));
      else store_arm_row(a, l, k, run.traces[static_cast<size_t>(l)]);
      if (!options.keep_q) continue;
      if (a.status[static_cast<size_t>(l)] == LaneStatus::kOk)
        for (int j = 0; j < nv; ++j) run.q[static_cast<size_t>(l)](j, k) = a.s.q[static_cast<size_t>(j * W + l)];
      else
        run.q[static_cast<size_t>(l)].col(k).setConstant(std::nan(""));
    }
    if (k + 1 == samples) break;
    step_arm_plant(a, k);
  }
  run.status = a.status;
  // A failed lane's trace is NaN from the sample it failed at: mark what it recorded after. (Its online
  // metrics need no marking: a failed lane's are all NaN.)
  for (int l = 0; l < W && !options.online; ++l)
    if (run.status[static_cast<size_t>(l)] != LaneStatus::kOk) mark_arm_trace_failure(a, run.traces[static_cast<size_t>(l)]);
  return run;
}

void write_arm_trace_csv(const ArmTrace& trace, const std::string& path) {
  std::ostringstream o;
  o.precision(17);
  for (std::size_t i = 0; i < trace.names.size(); ++i) o << (i ? "," : "") << trace.names[i];
  o << "\n";
  const std::size_t n = trace.columns.empty() ? 0 : trace.columns[0].size();
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t i = 0; i < trace.columns.size(); ++i) o << (i ? "," : "") << trace.columns[i][k];
    o << "\n";
  }
  write_file_atomic(path, o.str());
}

ArmTrace read_arm_trace_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  ArmTrace tr;
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(path + ":1: empty file");
  std::stringstream header(strip_bom(line));
  for (std::string name; std::getline(header, name, ',');) tr.names.push_back(name);
  check_csv_header(tr.names, path);
  tr.columns.resize(tr.names.size());
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    std::stringstream cells(line);
    std::size_t i = 0;
    for (std::string cell; std::getline(cells, cell, ','); ++i) {
      if (i >= tr.names.size()) throw std::runtime_error(path + ":" + std::to_string(row) + ": more cells than columns");
      try {
        tr.columns[i].push_back(std::stod(cell));
      } catch (const std::exception&) {
        throw std::runtime_error(path + ":" + std::to_string(row) + ": column " + tr.names[i] + ": not a number");
      }
    }
    if (i != tr.names.size()) throw std::runtime_error(path + ":" + std::to_string(row) + ": fewer cells than columns");
  }
  return tr;
}

}  // namespace ff
