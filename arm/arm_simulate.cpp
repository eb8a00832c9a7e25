// simulate_arms (arm_simulate.hpp): the sample loop over lanes.
#include "arm/arm_simulate.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "common/errors.hpp"
#include "common/files.hpp"
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
  for (const char* s : {"tool.x", "tool.y", "tool.z", "tool.ref_x", "tool.ref_y", "tool.ref_z"}) n.push_back(s);
  for (const LinkTip& l : m.links)
    for (const char* s : {".deflection_y", ".deflection_z"}) n.push_back(l.name + s);
  for (const ActuatedJoint& a : m.actuated)
    for (const char* s : {".q_measured", ".qd_measured"}) n.push_back(a.name + s);
  for (const ActuatedJoint& a : m.actuated)
    if (a.control.hydraulics.enabled)
      for (const char* s : {".pressure_a", ".pressure_b"}) n.push_back(a.name + s);
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
  if (a.control_period != b.control_period || a.duration != b.duration || a.substeps != b.substeps ||
      a.integrator != b.integrator || a.spec.rtol != b.spec.rtol || a.spec.atol != b.spec.atol)
    return "the rate, duration, substeps, integrator or its tolerances differ";
  return "";
}

namespace {

// Per-lane controller state and scratch, structure-of-arrays (joint j, lane l at [j * W + l]).
struct ControlLanes {
  int W = 0, na = 0;
  std::vector<double> integral, tau_held;
  std::vector<std::vector<double>> coef, state;  // per joint: notch coefficients and state (lanes innermost)
  std::vector<double> in, out;                   // (W) a notch's input and output
};

// The lane's tool point and, per flexible link, its tip deflection in the root frame.
void record_kinematics(const ArmModel& m, const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                       std::vector<Pose>& poses, double* out) {
  calc_body_poses(m.tree, q, poses);
  const Vec3 tool = poses[static_cast<std::size_t>(m.tool_body)].point(m.tool_point);
  out[0] = tool.x(), out[1] = tool.y(), out[2] = tool.z();
  int k = 6;
  for (const LinkTip& l : m.links) {
    const Pose& root = poses[static_cast<std::size_t>(l.root_body)];
    const Vec3 tip = poses[static_cast<std::size_t>(l.tip_body)].point(l.tip_point);
    const Vec3 d = root.rotation.transpose() * (tip - root.position) - l.rigid_tip;
    out[k++] = d.y();
    out[k++] = d.z();
  }
  calc_body_poses(m.tree, q_ref, poses);
  const Vec3 ref = poses[static_cast<std::size_t>(m.tool_body)].point(m.tool_point);
  out[3] = ref.x(), out[4] = ref.y(), out[5] = ref.z();
}

// ---- The replay hook (ArmRunOptions::reference) ----
// The reference of every actuated joint at controller sample k from the samples, with central differences.
void eval_replay_reference(const std::vector<std::vector<double>>& ref, long k, double T, double* r, double* rd,
                           double* rdd) {
  for (std::size_t j = 0; j < ref.size(); ++j) {
    const std::vector<double>& x = ref[j];
    const long n = static_cast<long>(x.size());
    auto at = [&](long i) { return x[static_cast<std::size_t>(std::clamp(i, 0L, n - 1))]; };
    r[j] = at(k);
    rd[j] = (at(k + 1) - at(k - 1)) / (2.0 * T);
    rdd[j] = (at(k + 1) - 2.0 * at(k) + at(k - 1)) / (T * T);
  }
}

}  // namespace

ArmRun simulate_arms(std::span<const ArmModel> lanes, const ArmRunOptions& options) {
  if (lanes.empty()) throw std::invalid_argument("simulate_arms: no lanes");
  const ArmModel& m0 = lanes[0];
  for (std::size_t l = 1; l < lanes.size(); ++l)
    if (const std::string why = explain_arm_shape_mismatch(m0, lanes[l]); !why.empty())
      throw std::invalid_argument("simulate_arms: lane " + std::to_string(l) + ": " + why);
  const int W = static_cast<int>(lanes.size());
  const int na = static_cast<int>(m0.actuated.size());
  if (options.reference) {  // the replay hook
    bool ok = options.reference->size() == static_cast<std::size_t>(na);
    for (const std::vector<double>& x : *options.reference) ok &= !x.empty();
    if (!ok) throw std::invalid_argument("simulate_arms: the reference needs one non-empty sample vector per actuated joint");
  }
  const int nv = m0.tree.nv();
  std::vector<Tree> trees;
  for (const ArmModel& m : lanes) trees.push_back(m.tree);
  TreeLanes tl = make_tree_lanes(trees);
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
  std::vector<int> hyd_joints;  // actuated joint index of actuator a
  for (int j = 0; j < na; ++j) {
    const ActuatedJoint& a0 = m0.actuated[static_cast<std::size_t>(j)];
    if (!a0.control.hydraulics.enabled) continue;
    std::vector<LaneDrive> p;
    std::vector<double> load;
    for (const ArmModel& m : lanes) {
      const ActuatedJoint& a = m.actuated[static_cast<std::size_t>(j)];
      p.push_back(make_hydraulic_drive(a.control.hydraulics));
      load.push_back(a.control.torque_offset);
    }
    add_tree_lanes_hydraulics(tl, a0.dof, p, load);
    hyd_joints.push_back(j);
  }
  const int nh = static_cast<int>(hyd_joints.size());
  TreeLanesState s = make_tree_lanes_state(tl);
  for (int a = 0; a < nh; ++a)
    for (int l = 0; l < W; ++l) {
      const auto [pa, pb] = calc_initial_pressures(lanes[l].actuated[static_cast<std::size_t>(hyd_joints[static_cast<std::size_t>(a)])]);
      s.z[static_cast<std::size_t>((kHydraulicStates * a + 2) * W + l)] = pa / kPressureUnit;
      s.z[static_cast<std::size_t>((kHydraulicStates * a + 3) * W + l)] = pb / kPressureUnit;
    }
  const std::vector<double> z0 = s.z;
  TreeStepWorkspace ws(tl);
  for (int l = 0; l < W; ++l)
    for (int j = 0; j < nv; ++j) {
      s.q[static_cast<std::size_t>(j * W + l)] = lanes[l].q0[j];
      s.qd[static_cast<std::size_t>(j * W + l)] = lanes[l].qd0.size() == nv ? lanes[l].qd0[j] : 0.0;
    }

  const double T = m0.control_period, h = T / m0.substeps;
  // The variable-step reference: CVODE per lane over each control period.
  std::unique_ptr<TreeCvode> cvode;
  std::vector<char> cvode_ok(static_cast<std::size_t>(W), 1);
  if (m0.integrator == Integrator::kCvodeDense || m0.integrator == Integrator::kCvodeKlu ||
      m0.integrator == Integrator::kCvodeGmres) {
    TreeCvodeOptions o;
    o.solver = m0.integrator == Integrator::kCvodeDense ? TreeCvodeSolver::kDense
               : m0.integrator == Integrator::kCvodeKlu ? TreeCvodeSolver::kKlu
                                                        : TreeCvodeSolver::kGmres;
    o.rtol = m0.spec.rtol;
    o.atol = m0.spec.atol;
    cvode = std::make_unique<TreeCvode>(tl, o);
  }
  const long samples = static_cast<long>(std::floor(m0.duration / T + 1e-9)) + 1;
  const std::vector<std::string> names = arm_trace_names(m0);
  ArmRun run;
  run.status.assign(static_cast<std::size_t>(W), LaneStatus::kOk);
  run.traces.resize(static_cast<std::size_t>(W));
  for (ArmTrace& tr : run.traces) {
    tr.names = names;
    tr.columns.assign(names.size(), std::vector<double>(static_cast<std::size_t>(samples), 0.0));
  }
  if (options.keep_q) run.q.assign(static_cast<std::size_t>(W), Eigen::MatrixXd::Zero(nv, samples));
  const std::size_t kin0 = 1 + 4 * static_cast<std::size_t>(na);  // first kinematic column
  const std::size_t hyd0 = names.size() - 2 * static_cast<std::size_t>(nh);  // first pressure column
  const std::size_t meas0 = hyd0 - 2 * static_cast<std::size_t>(na);           // first measured column

  // Controller state; each notch at rest at its first input.
  ControlLanes c;
  c.W = W, c.na = na;
  c.integral.assign(static_cast<std::size_t>(na * W), 0.0);
  c.tau_held.assign(static_cast<std::size_t>(na * W), 0.0);
  c.coef.resize(static_cast<std::size_t>(na));
  c.state.resize(static_cast<std::size_t>(na));
  c.in.assign(static_cast<std::size_t>(W), 0.0);
  c.out.assign(static_cast<std::size_t>(W), 0.0);
  std::vector<double> r(static_cast<std::size_t>(na * W)), rd(r.size()), rdd(r.size()), scratch(3 * static_cast<std::size_t>(na));
  std::vector<double> tau_id(static_cast<std::size_t>(na)), tau_g(static_cast<std::size_t>(na));
  for (int l = 0; l < W; ++l) {
    if (options.reference)  // the replay hook
      eval_replay_reference(*options.reference, 0, T, &r[static_cast<std::size_t>(l * na)],
                            &rd[static_cast<std::size_t>(l * na)], &rdd[static_cast<std::size_t>(l * na)]);
    else
      eval_arm_reference(lanes[l], 0.0, &r[static_cast<std::size_t>(l * na)], &rd[static_cast<std::size_t>(l * na)],
                         &rdd[static_cast<std::size_t>(l * na)], scratch.data());
  }
  for (int j = 0; j < na; ++j) {
    const int ns = static_cast<int>(m0.actuated[static_cast<std::size_t>(j)].notch.size());
    c.coef[static_cast<std::size_t>(j)].assign(static_cast<std::size_t>(5 * ns * W), 0.0);
    c.state[static_cast<std::size_t>(j)].assign(static_cast<std::size_t>(2 * ns * W), 0.0);
    for (int l = 0; l < W; ++l) {
      const ActuatedJoint& a = lanes[l].actuated[static_cast<std::size_t>(j)];
      if (ns == 0) continue;
      pack_notch_sections(a.notch, W, l, c.coef[static_cast<std::size_t>(j)].data());
      const double x0 = a.notch_on_feedback ? lanes[l].q0[a.dof] : r[static_cast<std::size_t>(l * na + j)];
      reset_notch_state(ns, W, l, c.coef[static_cast<std::size_t>(j)].data(), x0, c.state[static_cast<std::size_t>(j)].data());
    }
  }

  std::vector<ArmFeedforward> ff;
  for (const ArmModel& m : lanes) ff.emplace_back(m.tree);
  std::vector<Pose> poses(static_cast<std::size_t>(m0.tree.num_bodies()));
  Eigen::VectorXd q_lane(nv), q_ref(nv);
  std::vector<double> tau_applied(static_cast<std::size_t>(nv * W), 0.0), kin(names.size());
  std::vector<double> e(static_cast<std::size_t>(na * W));  // the control errors
  // The sensors: what each joint's controller measures (joint j, lane l at [j * W + l]), and per joint
  // and channel a ring of past readings (H x W), H the longest delay + hold of any joint and lane.
  int H = 1;
  for (const ArmModel& m : lanes)
    for (const ActuatedJoint& a : m.actuated)
      H = std::max({H, a.control.angle_sensor.delay + a.angle_hold, a.control.rate_sensor.delay + a.rate_hold});
  std::vector<double> q_meas(static_cast<std::size_t>(na * W)), qd_meas(q_meas.size());
  std::vector<std::vector<double>> ring_q(static_cast<std::size_t>(na), std::vector<double>(static_cast<std::size_t>(H * W), 0.0));
  std::vector<std::vector<double>> ring_qd = ring_q;

  for (long k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) * T;
    // What the sensors give the controllers now.
    for (int j = 0; j < na; ++j) {
      const int d = m0.actuated[static_cast<std::size_t>(j)].dof;
      for (int l = 0; l < W; ++l) {
        const ActuatedJoint& a = lanes[l].actuated[static_cast<std::size_t>(j)];
        const ChannelSpec &ca = a.control.angle_sensor, &cr = a.control.rate_sensor;
        const std::size_t jl = static_cast<std::size_t>(j * W + l), dl = static_cast<std::size_t>(d * W + l);
        q_meas[jl] = sample_channel(s.q[dl], ca.noise, a.angle_key, ca.resolution, ca.delay, a.angle_hold, k, H, W, l,
                                    ring_q[static_cast<std::size_t>(j)].data());
        qd_meas[jl] = sample_channel(s.qd[dl], cr.noise, a.rate_key, cr.resolution, cr.delay, a.rate_hold, k, H, W, l,
                                     ring_qd[static_cast<std::size_t>(j)].data());
      }
    }
    // The reference of every lane (its own trajectory and shapers).
    for (int l = 0; l < W; ++l) {
      if (options.reference)  // the replay hook
        eval_replay_reference(*options.reference, k, T, &r[static_cast<std::size_t>(l * na)],
                              &rd[static_cast<std::size_t>(l * na)], &rdd[static_cast<std::size_t>(l * na)]);
      else
        eval_arm_reference(lanes[l], t, &r[static_cast<std::size_t>(l * na)], &rd[static_cast<std::size_t>(l * na)],
                           &rdd[static_cast<std::size_t>(l * na)], scratch.data());
    }
    // The notch on each joint's reference or feedback, all lanes at once.
    for (int j = 0; j < na; ++j) {
      const ActuatedJoint& a0 = m0.actuated[static_cast<std::size_t>(j)];
      const int ns = static_cast<int>(a0.notch.size());
      for (int l = 0; l < W; ++l) {
        const double q = q_meas[static_cast<std::size_t>(j * W + l)];
        c.in[static_cast<std::size_t>(l)] = a0.notch_on_feedback ? q : r[static_cast<std::size_t>(l * na + j)];
      }
      if (ns > 0) step_notch(ns, W, c.coef[static_cast<std::size_t>(j)].data(), c.state[static_cast<std::size_t>(j)].data(), c.in.data(), c.out.data());
      else std::copy(c.in.begin(), c.in.end(), c.out.begin());
      for (int l = 0; l < W; ++l) {
        const double q = q_meas[static_cast<std::size_t>(j * W + l)];
        const double ref = r[static_cast<std::size_t>(l * na + j)];
        e[static_cast<std::size_t>(j * W + l)] = a0.notch_on_feedback ? ref - c.out[static_cast<std::size_t>(l)] : c.out[static_cast<std::size_t>(l)] - q;
      }
    }
    for (int l = 0; l < W; ++l) {
      const ArmModel& m = lanes[l];
      double* rl = &r[static_cast<std::size_t>(l * na)];
      double* rdl = &rd[static_cast<std::size_t>(l * na)];
      bool need_ff = false;
      for (const ActuatedJoint& a : m.actuated) need_ff |= a.control.feedforward != 0.0 || a.control.gravity_compensation != 0.0;
      if (need_ff) calc_arm_feedforward(m, rl, rdl, &rdd[static_cast<std::size_t>(l * na)], tau_id.data(), tau_g.data(), ff[static_cast<std::size_t>(l)]);
      // PID with clamping anti-windup, saturation, feed-forward.
      for (int j = 0; j < na; ++j) {
        const ActuatedJoint& a = m.actuated[static_cast<std::size_t>(j)];
        const std::size_t jl = static_cast<std::size_t>(j * W + l);
        const double qd = qd_meas[jl];
        const double err = e[jl];
        double u = a.control.kp * err + a.control.ki * c.integral[jl] - a.control.kd * qd;
        if (need_ff)
          u += a.control.feedforward * (tau_id[static_cast<std::size_t>(j)] - tau_g[static_cast<std::size_t>(j)] + a.control.kd * rdl[j]) +
               a.control.gravity_compensation * tau_g[static_cast<std::size_t>(j)];
        double tau = u;
        bool saturated = false;
        if (a.torque_limit > 0.0 && std::abs(u) > a.torque_limit) {
          tau = std::copysign(a.torque_limit, u);
          saturated = true;
        }
        if (!(saturated && err * u > 0.0)) c.integral[jl] += T * err;
        c.tau_held[jl] = tau;
      }
      // The trace at this sample.
      ArmTrace& tr = run.traces[static_cast<std::size_t>(l)];
      const std::size_t ks = static_cast<std::size_t>(k);
      tr.columns[0][ks] = t;
      for (int j = 0; j < na; ++j) {
        const ActuatedJoint& a = m.actuated[static_cast<std::size_t>(j)];
        tr.columns[static_cast<std::size_t>(1 + 4 * j)][ks] = rl[j];
        tr.columns[static_cast<std::size_t>(2 + 4 * j)][ks] = s.q[static_cast<std::size_t>(a.dof * W + l)];
        tr.columns[static_cast<std::size_t>(3 + 4 * j)][ks] = s.qd[static_cast<std::size_t>(a.dof * W + l)];
        tr.columns[static_cast<std::size_t>(4 + 4 * j)][ks] = c.tau_held[static_cast<std::size_t>(j * W + l)];
      }
      // A hydraulic joint's torque is its actuator's, D (p_a - p_b), and its chamber pressures (Pa).
      for (int a = 0; a < nh; ++a) {
        const std::size_t z = static_cast<std::size_t>(kHydraulicStates * a * W + l);
        const std::size_t col = hyd0 + 2 * static_cast<std::size_t>(a);
        tr.columns[static_cast<std::size_t>(4 + 4 * hyd_joints[static_cast<std::size_t>(a)])][ks] =
            eval_hydraulic_actuator(tl.hydraulics[static_cast<std::size_t>(a * W + l)], 0.0, 0.0, 0.0, s.z.data() + z,
                                    static_cast<std::size_t>(W), nullptr);
        tr.columns[col][ks] = s.z[z + 2 * static_cast<std::size_t>(W)] * kPressureUnit;
        tr.columns[col + 1][ks] = s.z[z + 3 * static_cast<std::size_t>(W)] * kPressureUnit;
      }
      if (run.status[static_cast<std::size_t>(l)] == LaneStatus::kOk) {
        q_ref.setZero();
        for (int j = 0; j < nv; ++j) q_lane[j] = s.q[static_cast<std::size_t>(j * W + l)];
        for (int j = 0; j < na; ++j) q_ref[m.actuated[static_cast<std::size_t>(j)].dof] = rl[j];
        record_kinematics(m, q_lane, q_ref, poses, kin.data());
        if (options.keep_q) run.q[static_cast<std::size_t>(l)].col(k) = q_lane;
      } else {
        std::fill(kin.begin(), kin.end(), std::nan(""));
        if (options.keep_q) run.q[static_cast<std::size_t>(l)].col(k).setConstant(std::nan(""));
      }
      for (std::size_t c2 = kin0; c2 < meas0; ++c2) tr.columns[c2][ks] = kin[c2 - kin0];
      for (int j = 0; j < na; ++j) {
        tr.columns[meas0 + 2 * static_cast<std::size_t>(j)][ks] = q_meas[static_cast<std::size_t>(j * W + l)];
        tr.columns[meas0 + 2 * static_cast<std::size_t>(j) + 1][ks] = qd_meas[static_cast<std::size_t>(j * W + l)];
      }
    }
    if (k + 1 == samples) break;
    // The plant over one period with the torques held, less each joint's constant load; a hydraulic
    // joint's held torque is its valve loop's command (the load is the actuator's, TreeLanes).
    for (int j = 0; j < na; ++j) {
      const ActuatedJoint& a0 = m0.actuated[static_cast<std::size_t>(j)];
      const bool hydraulic = a0.control.hydraulics.enabled;
      for (int l = 0; l < W; ++l)
        tau_applied[static_cast<std::size_t>(a0.dof * W + l)] =
            c.tau_held[static_cast<std::size_t>(j * W + l)] -
            (hydraulic ? 0.0 : lanes[l].actuated[static_cast<std::size_t>(j)].control.torque_offset);
    }
    if (cvode) {
      cvode->advance(tl, tau_applied.data(), s, t, T, cvode_ok);
      for (int l = 0; l < W; ++l)
        if (!cvode_ok[static_cast<std::size_t>(l)] && run.status[static_cast<std::size_t>(l)] == LaneStatus::kOk) {
          run.status[static_cast<std::size_t>(l)] = LaneStatus::kSolverFail;
          for (int j = 0; j < nv; ++j) s.q[static_cast<std::size_t>(j * W + l)] = std::nan("");
        }
    }
    for (int sub = 0; sub < (cvode ? 0 : m0.substeps); ++sub) {
      switch (m0.integrator) {
        case Integrator::kSdirk2: step_tree_sdirk2(tl, tau_applied.data(), s, ws, h); break;
        case Integrator::kMidpoint: step_tree_midpoint(tl, tau_applied.data(), s, ws, h); break;
        default: step_tree_rk4(tl, tau_applied.data(), s, ws, h); break;
      }
    }
    // A lane gone non-finite (or whose solver failed) is frozen at zero (its neighbours never see it:
    // lanes are independent).
    for (int l = 0; l < W; ++l) {
      if (run.status[static_cast<std::size_t>(l)] == LaneStatus::kNonfinite) continue;
      bool finite = true;
      for (int j = 0; j < nv; ++j)
        finite &= std::isfinite(s.q[static_cast<std::size_t>(j * W + l)]) && std::isfinite(s.qd[static_cast<std::size_t>(j * W + l)]);
      for (int i = 0; i < tl.nz(); ++i) finite &= std::isfinite(s.z[static_cast<std::size_t>(i * W + l)]);
      if (!finite) {
        if (run.status[static_cast<std::size_t>(l)] == LaneStatus::kOk) run.status[static_cast<std::size_t>(l)] = LaneStatus::kNonfinite;
        for (int j = 0; j < nv; ++j) {
          s.q[static_cast<std::size_t>(j * W + l)] = 0.0;
          s.qd[static_cast<std::size_t>(j * W + l)] = 0.0;
          s.a_prev[static_cast<std::size_t>(j * W + l)] = 0.0;
        }
        for (int i = 0; i < tl.nz(); ++i) s.z[static_cast<std::size_t>(i * W + l)] = z0[static_cast<std::size_t>(i * W + l)];
      }
    }
  }
  // A failed lane's trace is NaN from the sample it failed at: mark what it recorded after.
  for (int l = 0; l < W; ++l) {
    if (run.status[static_cast<std::size_t>(l)] == LaneStatus::kOk) continue;
    ArmTrace& tr = run.traces[static_cast<std::size_t>(l)];
    const std::vector<double>& x = tr.columns[kin0];
    std::size_t first = 0;
    while (first < x.size() && std::isfinite(x[first])) ++first;
    for (std::size_t c2 = 1; c2 < tr.columns.size(); ++c2)
      for (std::size_t k = first; k < tr.columns[c2].size(); ++k) tr.columns[c2][k] = std::nan("");
  }
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
  std::stringstream header(line);
  for (std::string name; std::getline(header, name, ',');) tr.names.push_back(name);
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
