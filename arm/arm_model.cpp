// make_arm (arm_model.hpp): the tree, the actuated joints, the tool, the trajectory (IK at plan time),
// the initial sag, the closed-loop modes and from them the substeps, notches and shapers.
#include "arm/arm_model.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "kernel/batch.hpp"  // calc_sensor_hold
#include "common/closest.hpp"
#include "common/errors.hpp"
#include "common/field_table.hpp"
#include "kernel/drive.hpp"
#include "kernel/friction.hpp"
#include "kernel/modes.hpp"
#include "common/random.hpp"
#include "common/units_check.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/inverse_kinematics.hpp"
#include "multibody/modes.hpp"
#include "multibody/statics.hpp"

namespace ff {

namespace {

ShaperKind parse_shaper_kind(const std::string& type) {
  if (type == "zv") return ShaperKind::kZv;
  if (type == "zvd") return ShaperKind::kZvd;
  if (type == "ei") return ShaperKind::kEi;
  return ShaperKind::kNone;
}

std::string joint_key(const ActuatedJoint& a, const std::string& tail) { return "joints." + a.name + "." + tail; }

// A tool point: its body by name ("" = the last body; a flexible link's name means its tip segment, the
// point then from the tip point, as the last body's when that is a link's tip), errors at `key`body.
ArmTool resolve_tool(const ArmModel& m, const ArmSpec& spec, const ToolSpec& t, const std::string& key) {
  ArmTool out{t.name, m.tree.num_bodies() - 1, t.point};
  bool at_link_tip = false;
  if (!t.body.empty()) {
    const auto link = std::find_if(m.links.begin(), m.links.end(), [&](const LinkTip& l) { return l.name == t.body; });
    if (link != m.links.end()) {
      out.body = link->tip_body;
      out.point = link->tip_point + t.point;
      at_link_tip = true;
    } else {
      const auto it = spec.tree.body_index.find(t.body);
      if (it == spec.tree.body_index.end())
        throw ConfigError(spec.source, t.line, key + "body",
                          "no body named '" + t.body + "'" + format_did_you_mean(t.body, list_body_names(spec.tree)));
      out.body = it->second;
    }
  }
  if (!at_link_tip && t.body.empty())
    for (const LinkTip& l : m.links)
      if (l.tip_body == out.body) out.point = l.tip_point + t.point;
  return out;
}

std::string tool_names(const ArmModel& m) {
  std::string s;
  for (const ArmTool& t : m.tools) s += (s.empty() ? "" : ", ") + t.name;
  return s;
}

std::string did_you_mean_tool(const ArmModel& m, const std::string& wrong) {
  std::vector<std::string> names;
  for (const ArmTool& t : m.tools) names.push_back(t.name);
  return format_did_you_mean(wrong, names);
}

// The safety monitors (`monitors:`): each one's type, action, watched joint, link or tool by index, its
// samples; errors at monitors.NAME.KEY on the block's line. After the tools, links, collision, period.
void make_monitors(ArmModel& m) {
  const ArmSpec& spec = m.spec;
  const double T = m.control_period;
  // Whole controller samples of a time, rounded up (within 1e-9 of a sample: as calc_arm_samples).
  auto samples_of = [&](double t) { return static_cast<long>(std::ceil(t / T - 1e-9)); };
  for (const MonitorSpec& s : spec.monitors) {
    const std::string key = "monitors." + s.name + ".";
    auto fail = [&](const std::string& k, const std::string& why) { throw ConfigError(spec.source, s.line, key + k, why); };
    ArmMonitor o;
    o.name = s.name;
    if (!parse_monitor_type(s.type, o.type))
      fail("type", "unknown monitor type '" + s.type + "' (" + std::string(kMonitorTypes) + ")");
    if (!parse_monitor_action(s.action, o.action))
      fail("action", "unknown action '" + s.action + "' (record, hold, stop, brake)");
    if (o.type == MonitorType::kJointTorque || o.type == MonitorType::kJointSpeed) {
      for (std::size_t j = 0; j < m.actuated.size(); ++j)
        if (m.actuated[j].name == s.joint) o.joint = static_cast<int>(j);
      if (o.joint < 0) {
        std::vector<std::string> names;
        std::string known;
        for (const ActuatedJoint& a : m.actuated) names.push_back(a.name), known += (known.empty() ? "" : ", ") + a.name;
        fail("joint", "no actuated joint named '" + s.joint + "'" + format_did_you_mean(s.joint, names) + " (actuated: " + known + ")");
      }
    }
    if (o.type == MonitorType::kDeflection) {
      for (std::size_t i = 0; i < m.links.size(); ++i)
        if (m.links[i].name == s.link) o.link = static_cast<int>(i);
      std::vector<std::string> names;
      for (const LinkTip& l : m.links) names.push_back(l.name);
      if (o.link < 0) fail("link", "no flexible link named '" + s.link + "'" + format_did_you_mean(s.link, names));
    }
    if (!s.tool.empty()) {
      o.tool = -1;
      for (std::size_t t = 0; t < m.tools.size(); ++t)
        if (m.tools[t].name == s.tool) o.tool = static_cast<int>(t);
      if (o.tool < 0) fail("tool", "no tool named '" + s.tool + "'" + did_you_mean_tool(m, s.tool) + " (tools: " + tool_names(m) + ")");
    }
    if (o.type == MonitorType::kClearance && !m.collision.active())
      fail("type", "a clearance monitor needs a world (`world:`) or another arm to measure the clearance to");
    if (o.type == MonitorType::kWorkspace)
      for (int i = 0; i < 3; ++i)
        if (!(s.lower[i] < s.upper[i])) fail("upper", "must exceed lower in x, y and z");
    if (!std::isfinite(s.limit)) fail("limit", "must be finite");
    o.limit = s.limit;
    o.lower = s.lower;
    o.upper = s.upper;
    o.command_sample = samples_of(s.time);
    o.delay_samples = samples_of(s.delay);
    o.deceleration = s.deceleration;
    o.brake_torque = s.brake_torque;
    if (o.action == MonitorAction::kBrake && o.brake_torque == 0.0)
      for (const ActuatedJoint& a : m.actuated)
        if (!(a.torque_limit > 0.0))
          fail("brake_torque", "missing: joint " + a.name + " has no torque limit to saturate the brake at");
    for (const ArmMonitor& p : m.monitors)
      if (p.name == o.name) fail("type", "a monitor of that name is given already");
    m.monitors.push_back(std::move(o));
  }
  // The brakes' gains: each actuated joint's own inertia at the start over the sample time.
  bool brake = false;
  for (const ArmMonitor& o : m.monitors) brake |= o.action == MonitorAction::kBrake;
  if (!brake) return;
  Eigen::MatrixXd M(m.tree.nv(), m.tree.nv());
  TreeWorkspace ws(m.tree);
  calc_mass_matrix(m.tree, m.q0, M, ws);
  for (const ActuatedJoint& a : m.actuated) m.brake_gain.push_back(M(a.dof, a.dof) / T);
}

// The joint info of the body whose joint is `dof`.
const JointInfo& joint_info(const ArmSpec& spec, const Tree& tree, int dof) {
  for (int i = 0; i < tree.num_bodies(); ++i)
    if (tree.body(i).dof == dof) return spec.tree.joints[static_cast<std::size_t>(i)];
  throw std::logic_error("joint_info: no body moves dof " + std::to_string(dof));
}

// A joint's friction, torque offset and sensors, checked as the rig checks its hub's (kernel/model.cpp).
void check_joint_blocks(const ArmSpec& spec, const JointControlSpec& c) {
  const std::string& src = spec.source;
  const std::string key = "joints." + c.joint + ".";
  auto non_negative = [&](double x, const std::string& k) {
    if (!(x >= 0.0)) throw ConfigError(src, 0, key + k, "must be >= 0, got " + format_key_number(x));
  };
  auto positive = [&](double x, const std::string& k) {
    if (!(x > 0.0)) throw ConfigError(src, 0, key + k, "must be > 0, got " + format_key_number(x));
  };
  const FrictionSpec& f = c.friction;
  non_negative(f.viscous, "friction.viscous");
  non_negative(f.coulomb, "friction.coulomb");
  non_negative(f.stiction, "friction.stiction");
  if (f.stiction > 0 && f.stiction < f.coulomb)
    throw ConfigError(src, 0, key + "friction.stiction", "must be >= friction.coulomb (or 0 for no Stribeck peak)");
  positive(f.stribeck_velocity, "friction.stribeck_velocity");
  positive(f.smoothing, "friction.smoothing");
  if (f.model != "static" && f.model != "lugre")
    throw ConfigError(src, 0, key + "friction.model", "unknown friction model '" + f.model + "' (static, lugre)");
  if (f.model == "lugre") {
    positive(f.coulomb, "friction.coulomb");
    positive(f.bristle_stiffness, "friction.bristle_stiffness");
    non_negative(f.bristle_damping, "friction.bristle_damping");
  }
  if (c.drive) {
    non_negative(c.train.cubic_stiffness, "drive.cubic_stiffness");
    non_negative(c.train.backlash, "drive.backlash");
    if (!(c.train.efficiency > 0.0 && c.train.efficiency <= 1.0))
      throw ConfigError(src, 0, key + "drive.efficiency", "must be in (0, 1], got " + format_key_number(c.train.efficiency));
  }
  if (!std::isfinite(c.torque_offset)) throw ConfigError(src, 0, key + "torque_offset", "must be finite");
  if (c.hydraulics.enabled) {
    if (c.drive)
      throw ConfigError(src, 0, key + "hydraulics",
                        "a joint has either a compliant drive train (drive:) or a hydraulic actuator (hydraulics:), not both");
    if (const auto [k, why] = explain_hydraulic_fault(c.hydraulics); !k.empty())
      throw ConfigError(src, 0, key + "hydraulics." + k, why);
  }
  for (const auto& [ch, name] : {std::pair{&c.angle_sensor, "sensors.angle"}, std::pair{&c.rate_sensor, "sensors.rate"}}) {
    const std::string k(name);
    non_negative(ch->resolution, k + ".resolution");
    non_negative(ch->noise, k + ".noise");
    if (!std::isfinite(ch->resolution) || !std::isfinite(ch->noise))
      throw ConfigError(src, 0, key + k, "resolution and noise must be finite");
    if (ch->delay < 0 || ch->delay > 10000)
      throw ConfigError(src, 0, key + k + ".delay", "must be between 0 and 10000 samples");
    non_negative(ch->rate, k + ".rate");
    if (!is_logged_name(ch->logged))
      throw ConfigError(src, 0, key + k + ".logged",
                        "unknown value '" + ch->logged + "' (read: what the controller read, true: on time)");
    if (ch->logged_delay < 0 || ch->logged_delay > 10000)
      throw ConfigError(src, 0, key + k + ".logged_delay", "must be between 0 and 10000 samples");
    if (ch->rate > 0) {
      const double ratio = spec.rate / ch->rate;
      if (!(ratio >= 1.0 - 1e-9) || std::fabs(ratio - std::round(ratio)) > 1e-9 * ratio || ratio > 1e6)
        throw ConfigError(src, 0, key + k + ".rate",
                          "must divide controller.rate = " + std::to_string(spec.rate) + " Hz a whole number of times, got " +
                              std::to_string(ch->rate) + " Hz");
    }
  }
}

// The fastest rate (1/s) of the joints' own dynamics a fixed step must resolve, on each joint's
// effective inertia J_eff = 1 / (M^-1)_jj at q (what the joint moves with everything else free: the
// stiffest case):
// - friction (RK4 and midpoint only): the map's slope (b + max(Fc, Fs) / eps) / J_eff is a real
//   eigenvalue; RK4 is stable to h rate = 2.78 (allowed 2.5); the midpoint rule takes the friction
//   backward-Euler implicit and follows at h rate <= 250 (the rig's bound, kernel/drive.cpp); SDIRK2
//   and CVODE need nothing;
// - a hydraulic actuator (every fixed-step method, h rate <= 1, as the rig's hub drive:
//   calc_hydraulic_rate): spool, torque loop, relief valves, the oil spring on J_eff;
// - LuGre friction (every fixed-step method, h rate <= 1, as the rig's, kernel/drive.cpp
//   calc_drive_rate): the stuck bristles' spring and damper on J_eff, sqrt(sigma0 / J_eff) and
//   sigma1 / J_eff, and their relaxation at 1 rad/s, sigma0 / Fc (the bristle state itself is solved
//   exactly in each implicit stage, its torque acts explicitly).
// 0 without any.
double calc_joint_rate(const ArmModel& m, const Eigen::VectorXd& q, Integrator integ) {
  const bool friction_counts = integ == Integrator::kRk4 || integ == Integrator::kMidpoint;
  bool any = false;
  for (const ActuatedJoint& a : m.actuated)
    any = any || a.control.hydraulics.enabled || a.control.friction.model == "lugre" ||
          (friction_counts && is_friction_on(make_friction_map(a.control.friction)));
  if (!any) return 0.0;
  const int n = m.tree.nv();
  Eigen::MatrixXd M(n, n);
  TreeWorkspace ws(m.tree);
  calc_mass_matrix(m.tree, q, M, ws);
  const Eigen::MatrixXd Minv = M.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  double rate = 0.0;
  for (const ActuatedJoint& a : m.actuated) {
    const FrictionSpec& f = a.control.friction;
    if (f.model == "lugre") {
      const double inv_j = Minv(a.dof, a.dof);
      rate = std::max({rate, std::sqrt(f.bristle_stiffness * inv_j), f.bristle_damping * inv_j,
                       f.bristle_stiffness / f.coulomb});
    } else if (friction_counts && is_friction_on(make_friction_map(f))) {
      const double slope = (f.viscous + std::max(f.coulomb, f.stiction) / f.smoothing) * Minv(a.dof, a.dof);
      rate = std::max(rate, integ == Integrator::kRk4 ? slope / 2.5 : slope / 250.0);
    }
    if (a.control.hydraulics.enabled)
      rate = std::max(rate, calc_hydraulic_rate(make_hydraulic_drive(a.control.hydraulics), 1.0 / Minv(a.dof, a.dof)));
  }
  return rate;
}

// The torque each hydraulic joint holds at rest at q: its gravity load g(q), its own spring
// k (q - q_ref) and its torque offset (nh, in actuated order); each actuator's chambers must carry it.
std::vector<double> calc_hold_torques(const ArmModel& m, const Eigen::VectorXd& q) {
  std::vector<double> hold;
  bool any = false;
  for (const ActuatedJoint& a : m.actuated) any = any || a.control.hydraulics.enabled;
  if (!any) return hold;
  TreeWorkspace ws(m.tree);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m.tree.nv());
  Eigen::VectorXd g(m.tree.nv());
  calc_bias_forces(m.tree, q, zero, g, ws);
  for (const ActuatedJoint& a : m.actuated) {
    if (!a.control.hydraulics.enabled) continue;
    const Body& b = m.tree.body(a.body);
    hold.push_back(g[a.dof] + b.stiffness * (q[a.dof] - b.spring_reference) + a.control.torque_offset);
  }
  return hold;
}

void set_hold_torques(ArmModel& m, const Eigen::VectorXd& q) {
  const std::vector<double> hold = calc_hold_torques(m, q);
  std::size_t i = 0;
  for (ActuatedJoint& a : m.actuated) {
    const HydraulicSpec& h = a.control.hydraulics;
    if (!h.enabled) continue;
    a.hold_torque = hold[i++];
    const double stall = calc_displacement(h) * (h.supply_pressure - h.tank_pressure);
    if (!(std::abs(a.hold_torque) <= stall))
      throw ConfigError(m.spec.source, 0, joint_key(a, "hydraulics"),
                        "the actuator cannot hold the joint at the start: its static load " + std::to_string(a.hold_torque) +
                            " exceeds D (p_s - p_t) = " + std::to_string(stall));
  }
}

// One hydraulic actuator linearised at rest at pinion angle theta holding `hold` (chambers at
// (p_s + p_t)/2 +- hold / (2 D), spool centred), its valve loop commanded by the PD:
// demand = hold - kp dtheta - kd domega. Central differences (at the centred spool the lands' flow gains
// of either side averaged), per unit of the stored states (MPa): the torque's row dtau/dz (4), the
// rates' columns df/dtheta, df/domega (4 each) and df/dz (4 x 4, column-major).
void linearise_actuator(const ActuatedJoint& a, double theta, double hold, double* dtau, double* dq, double* dqd,
                        double* dz) {
  constexpr int n = kHydraulicStates;
  const HydraulicSpec& h = a.control.hydraulics;
  const LaneDrive p = make_hydraulic_drive(h);
  const double mean = 0.5 * (h.supply_pressure + h.tank_pressure), half = 0.5 * hold / p.D;
  const double x0[n] = {0.0, 0.0, (mean + half) / kPressureUnit, (mean - half) / kPressureUnit};
  const double kp = a.control.kp, kd = a.control.kd;
  auto rates = [&](const double* x, double dth, double dw, double* f) {
    return eval_hydraulic_actuator(p, hold - kp * dth - kd * dw, theta + dth, dw, x, 1, f);
  };
  double xp[n], xm[n], fp[n], fm[n];
  for (int j = 0; j < n; ++j) {
    std::copy(x0, x0 + n, xp);
    std::copy(x0, x0 + n, xm);
    const double d = 1e-6 * std::max(std::abs(x0[j]), 1.0);
    xp[j] += d;
    xm[j] -= d;
    dtau[j] = (rates(xp, 0.0, 0.0, fp) - rates(xm, 0.0, 0.0, fm)) / (2.0 * d);
    for (int i = 0; i < n; ++i) dz[j * n + i] = (fp[i] - fm[i]) / (2.0 * d);
  }
  const double d = 1e-6;
  rates(x0, d, 0.0, fp);
  rates(x0, -d, 0.0, fm);
  for (int i = 0; i < n; ++i) dq[i] = (fp[i] - fm[i]) / (2.0 * d);
  rates(x0, 0.0, d, fp);
  rates(x0, 0.0, -d, fm);
  for (int i = 0; i < n; ++i) dqd[i] = (fp[i] - fm[i]) / (2.0 * d);
}

}  // namespace

TreeModeOptions make_arm_loop_options(const ArmModel& m, const Eigen::VectorXd& q) {
  const int n = m.tree.nv();
  TreeModeOptions o;
  o.extra_stiffness = Eigen::MatrixXd::Zero(n, n);
  o.extra_damping = Eigen::MatrixXd::Zero(n, n);
  const std::vector<double> hold = calc_hold_torques(m, q);
  const int nz = kHydraulicStates * static_cast<int>(hold.size());
  if (nz > 0) {
    o.actuator_force = Eigen::MatrixXd::Zero(n, nz);
    o.actuator_q = Eigen::MatrixXd::Zero(nz, n);
    o.actuator_qd = Eigen::MatrixXd::Zero(nz, n);
    o.actuator_z = Eigen::MatrixXd::Zero(nz, nz);
  }
  int z = 0;
  for (const ActuatedJoint& a : m.actuated) {
    if (!a.control.hydraulics.enabled) {
      o.extra_stiffness(a.dof, a.dof) = a.control.kp;
      o.extra_damping(a.dof, a.dof) = a.control.kd;
      continue;
    }
    constexpr int k = kHydraulicStates;
    double dtau[k], dq[k], dqd[k], dz[k * k];
    linearise_actuator(a, q[a.dof], hold[static_cast<std::size_t>(z / k)], dtau, dq, dqd, dz);
    for (int i = 0; i < k; ++i) {
      o.actuator_force(a.dof, z + i) = dtau[i];
      o.actuator_q(z + i, a.dof) = dq[i];
      o.actuator_qd(z + i, a.dof) = dqd[i];
      for (int j = 0; j < k; ++j) o.actuator_z(z + i, z + j) = dz[j * k + i];
    }
    z += k;
  }
  return o;
}

std::vector<TreeMode> calc_arm_closed_loop_modes(const ArmModel& m, const Eigen::VectorXd& q) {
  return calc_tree_modes(m.tree, q, make_arm_loop_options(m, q));
}

ArmModel make_arm(const ArmSpec& spec, std::shared_ptr<const ArmModel> controller) {
  const std::string& src = spec.source;
  ArmModel m;
  m.spec = spec;
  m.tree = make_tree(spec.tree.spec);
  const int nv = m.tree.nv();

  // The actuated joints, in dof order.
  std::map<int, const JointControlSpec*> by_dof;
  for (const JointControlSpec& c : spec.joints) {
    const auto it = spec.tree.dof_index.find(c.joint);
    if (it == spec.tree.dof_index.end())
      throw ConfigError(src, 0, "joints." + c.joint,
                        "no moving joint of that name" + format_did_you_mean(c.joint, list_joint_names(spec.tree)));
    check_joint_blocks(spec, c);
    if (!by_dof.emplace(it->second, &c).second)
      throw ConfigError(src, 0, "joints." + c.joint, "this joint has a controller already");
  }
  std::vector<char> actuated(static_cast<std::size_t>(nv), 0);
  for (const auto& [dof, c] : by_dof) {
    ActuatedJoint a;
    a.name = c->joint;
    a.dof = dof;
    a.control = *c;
    const JointInfo& info = joint_info(spec, m.tree, dof);
    a.torque_limit = c->torque_limit > 0.0 ? c->torque_limit : (std::isfinite(info.effort) ? info.effort : 0.0);
    a.notch_on_feedback = c->notch.placement == "feedback";
    for (int i = 0; i < m.tree.num_bodies(); ++i)
      if (m.tree.body(i).dof == dof) a.body = i;
    const std::uint64_t i = m.actuated.size();
    a.angle_hold = calc_sensor_hold(c->angle_sensor, spec.rate);
    a.rate_hold = calc_sensor_hold(c->rate_sensor, spec.rate);
    a.angle_key = calc_variant_seed(spec.seed, 2 * i);
    a.rate_key = calc_variant_seed(spec.seed, 2 * i + 1);
    m.actuated.push_back(std::move(a));
    actuated[static_cast<std::size_t>(dof)] = 1;
  }
  for (int j = 0; j < nv; ++j)
    if (!actuated[static_cast<std::size_t>(j)]) m.passive_dofs.push_back(j);
  const int na = static_cast<int>(m.actuated.size());

  // The flexible links, and the tool: a body by name (a flexible link's name means its tip).
  for (const FlexibleLinkInfo& f : spec.tree.flexible_links) {
    LinkTip t;
    t.name = f.name;
    t.root_body = f.root_body;
    t.tip_body = f.tip_body;
    t.tip_point = f.tip_point;
    t.rigid_tip = Vec3(f.link.length, 0.0, 0.0);
    t.elastic_dofs = f.dofs;
    m.links.push_back(std::move(t));
  }
  for (const LinkTip& l : m.links) m.compliant_dofs.insert(m.compliant_dofs.end(), l.elastic_dofs.begin(), l.elastic_dofs.end());
  for (const JointControlSpec& c : spec.joints)
    if (c.drive) m.compliant_dofs.push_back(spec.tree.dof_index.at(c.joint + ".twist"));
  // The tools: `tool:`'s one, named "tool", or `tools:`'s by name. Their names head trace columns and
  // metrics (<name>.x, <name>_settling_s), so none may be an actuated joint's or a flexible link's.
  if (spec.tools.empty()) {
    m.tools.push_back(resolve_tool(m, spec, {"tool", spec.tool_body, spec.tool_point, 0}, "tool."));
  } else {
    for (const ToolSpec& t : spec.tools) {
      const std::string key = "tools." + t.name;
      for (const ArmTool& o : m.tools)
        if (o.name == t.name) throw ConfigError(src, t.line, key, "a tool of that name is given already");
      for (const JointControlSpec& c : spec.joints)
        if (c.joint == t.name)
          throw ConfigError(src, t.line, key, "an actuated joint has that name: its columns and metrics would clash");
      for (const LinkTip& l : m.links)
        if (l.name == t.name)
          throw ConfigError(src, t.line, key, "a flexible link has that name: its columns and metrics would clash");
      m.tools.push_back(resolve_tool(m, spec, t, key + "."));
    }
  }
  m.tool_body = m.tools.front().body;
  m.tool_point = m.tools.front().point;
  // What the arm can touch: its capsules, the world's obstacles, the pairs between arms.
  m.collision = make_arm_collision(m, spec.world, spec.collision);

  // The trajectory: joint waypoints as written, tool waypoints by IK on the rigid arm (flexible links
  // straight), each from the pose before it.
  m.trajectory.shape = spec.shape;
  // A revolute joint's angle beyond a turn: degrees, unless the file allows it (`units_check: false`).
  auto check_angle = [&](const std::string& joint, double value, int line, const std::string& key) {
    const int dof = spec.tree.dof_index.at(joint);
    for (int i = 0; i < m.tree.num_bodies() && spec.units_check; ++i)
      if (m.tree.body(i).dof == dof && m.tree.body(i).joint == JointType::kRevolute && !explain_angle_unit(value).empty())
        throw ConfigError(src, line, key, explain_angle_unit(value));
  };
  Eigen::VectorXd pose = Eigen::VectorXd::Zero(nv);
  for (const auto& [name, value] : spec.start) {
    if (!std::isfinite(value)) throw ConfigError(src, spec.start_line, "trajectory.start." + name, "must be finite");
    check_angle(name, value, spec.start_line, "trajectory.start." + name);
    pose[spec.tree.dof_index.at(name)] = value;
  }
  for (const ActuatedJoint& a : m.actuated) m.trajectory.start.push_back(pose[a.dof]);
  std::map<std::string, int> act_index;
  for (int k = 0; k < na; ++k) act_index[m.actuated[static_cast<std::size_t>(k)].name] = k;
  IkOptions ik;
  for (const ActuatedJoint& a : m.actuated) {
    ik.free_dofs.push_back(a.dof);
  }
  ik.lower.assign(static_cast<std::size_t>(nv), -JointInfo::kNone);
  ik.upper.assign(static_cast<std::size_t>(nv), JointInfo::kNone);
  for (int j = 0; j < nv; ++j) {
    const JointInfo& info = joint_info(spec, m.tree, j);
    ik.lower[static_cast<std::size_t>(j)] = info.lower;
    ik.upper[static_cast<std::size_t>(j)] = info.upper;
  }
  for (std::size_t w = 0; w < spec.waypoints.size(); ++w) {
    const ArmWaypoint& wp = spec.waypoints[w];
    const std::string key = "trajectory.waypoints[" + std::to_string(w) + "]";
    if (na == 0) throw ConfigError(src, wp.line, key, "the arm has no actuated joint to move (give `joints`)");
    // Joint values as written (a `tools` waypoint's fix those joints before its IK).
    for (const auto& [name, value] : wp.joints) {
      const auto it = act_index.find(name);
      if (it == act_index.end())
        throw ConfigError(src, wp.line, key + ".joints." + name,
                          spec.tree.dof_index.count(name) ? "a passive joint cannot be commanded (give it a controller under `joints`)"
                                                          : "no moving joint of that name" + format_did_you_mean(name, list_joint_names(spec.tree)));
      if (!std::isfinite(value)) throw ConfigError(src, wp.line, key + ".joints." + name, "must be finite");
      check_angle(name, value, wp.line, key + ".joints." + name);
      pose[m.actuated[static_cast<std::size_t>(it->second)].dof] = value;
    }
    if (wp.cartesian) {
      if (m.tools.size() != 1)
        throw ConfigError(src, wp.line, key + ".tool",
                          "this arm has several tools (" + tool_names(m) + "): give `tools: {NAME: [x, y, z], ...}`");
      IkTarget target;
      target.body = m.tool_body;
      target.point = m.tool_point;
      target.position = wp.tool;
      const IkResult r = solve_inverse_kinematics(m.tree, pose, target, ik);
      if (!r.converged) throw ConfigError(src, wp.line, key + ".tool", "the tool cannot reach it: " + r.why);
      pose = r.q;
    } else if (!wp.tools.empty()) {
      // Every named tool's target at once: the stacked tasks over the actuated joints this waypoint
      // does not fix.
      std::vector<IkTarget> targets;
      for (const auto& tool_target : wp.tools) {
        // Named, not bound: clang 14 cannot capture a structured binding in a lambda (C++20, clang 16).
        const std::string& name = tool_target.first;
        const auto& position = tool_target.second;
        const auto t = std::find_if(m.tools.begin(), m.tools.end(), [&](const ArmTool& x) { return x.name == name; });
        if (t == m.tools.end())
          throw ConfigError(src, wp.line, key + ".tools." + name,
                            "no tool of that name" + did_you_mean_tool(m, name) + " (tools: " + tool_names(m) + ")");
        if (!position.allFinite()) throw ConfigError(src, wp.line, key + ".tools." + name, "must be finite");
        targets.push_back({.body = t->body, .point = t->point, .position = position, .name = name});
      }
      IkOptions free = ik;
      free.free_dofs.clear();
      for (const ActuatedJoint& a : m.actuated)
        if (std::none_of(wp.joints.begin(), wp.joints.end(), [&](const auto& j) { return j.first == a.name; }))
          free.free_dofs.push_back(a.dof);
      if (free.free_dofs.empty())
        throw ConfigError(src, wp.line, key + ".tools", "`joints` fixes every actuated joint: none is left for the tools");
      const IkResult r = solve_inverse_kinematics(m.tree, pose, targets, free);
      if (!r.converged)
        throw ConfigError(src, wp.line, key + ".tools",
                          std::string(targets.size() == 1 ? "the tool cannot reach it: " : "the tools cannot reach them: ") + r.why);
      pose = r.q;
    }
    JointWaypoint jw;
    jw.time = wp.time;
    for (const ActuatedJoint& a : m.actuated) jw.q.push_back(pose[a.dof]);
    for (int k = 0; k < na; ++k) {
      const JointInfo& info = joint_info(spec, m.tree, m.actuated[static_cast<std::size_t>(k)].dof);
      if (jw.q[static_cast<std::size_t>(k)] < info.lower || jw.q[static_cast<std::size_t>(k)] > info.upper)
        throw ConfigError(src, wp.line, key, "joint " + m.actuated[static_cast<std::size_t>(k)].name + " at " +
                                                 format_key_number(jw.q[static_cast<std::size_t>(k)]) + " is beyond its limits [" +
                                                 format_key_number(info.lower) + ", " + format_key_number(info.upper) + "] (rad or m)");
    }
    m.trajectory.waypoints.push_back(std::move(jw));
  }
  m.move_end = spec.waypoints.empty() ? 0.0 : spec.waypoints.back().time;
  m.control_period = 1.0 / spec.rate;
  m.duration = spec.duration > 0.0 ? spec.duration : m.move_end + spec.settle;
  if (!(m.duration >= m.control_period))
    throw ConfigError(src, 0, "simulation.duration", "shorter than one control period: give a duration or waypoints");

  // The initial state: at rest, every joint at its start (0 unless `trajectory.start` says), the flexible links
  // sagging under gravity.
  Eigen::VectorXd start = Eigen::VectorXd::Zero(nv);
  for (const auto& [name, value] : spec.start) start[spec.tree.dof_index.at(name)] = value;
  m.q0 = calc_arm_sag(m, start).q;
  m.qd0 = Eigen::VectorXd::Zero(nv);
  set_hold_torques(m, m.q0);
  make_monitors(m);

  // Closed-loop modes: the integrator's substeps, and the notches and shapers designed on them.
  m.integrator = spec.integrator_given ? spec.integrator : (m.links.empty() ? Integrator::kRk4 : Integrator::kSdirk2);
  const std::vector<TreeMode> modes = calc_arm_closed_loop_modes(m, m.q0);
  std::vector<Mode> kernel_modes;
  std::vector<double> zetas;
  for (const TreeMode& md : modes) {
    kernel_modes.push_back({md.omega_n, md.zeta, md.oscillatory});
    if (md.oscillatory && md.zeta < 0.3 && md.omega_n > 0.0) {
      m.resonances.push_back(md.omega_n);
      zetas.push_back(md.zeta);
    }
  }
  const bool cvode = m.integrator == Integrator::kCvodeDense || m.integrator == Integrator::kCvodeKlu ||
                     m.integrator == Integrator::kCvodeGmres;
  m.substeps = cvode ? 1 : spec.substeps > 0 ? spec.substeps : calc_auto_substeps(kernel_modes, m.control_period, m.integrator);
  if (!cvode && spec.substeps == 0)
    m.substeps = std::max(m.substeps, calc_substeps_for_rate(calc_joint_rate(m, m.q0, m.integrator), m.control_period));
  if (m.substeps > kMaxSubsteps)
    throw ConfigError(src, 0, "simulation.substeps",
                      "the automatic step would need more than 100000 substeps per controller sample: a mode or a "
                      "joint's drive is far too fast for the controller's rate; check the model's values");
  if (controller) {
    // The controller's model designed the notches, shapers, trajectory (its IK) and brakes; its
    // controller-side blocks are this spec's, only plant-side values differ.
    if (controller->actuated.size() != m.actuated.size())
      throw ConfigError(src, 0, "joints", "the controller's model has other actuated joints than the plant");
    for (std::size_t j = 0; j < m.actuated.size(); ++j) {
      m.actuated[j].shaper = controller->actuated[j].shaper;
      m.actuated[j].notch = controller->actuated[j].notch;
      m.actuated[j].notch_on_feedback = controller->actuated[j].notch_on_feedback;
    }
    m.trajectory = controller->trajectory;
    m.brake_gain = controller->brake_gain;
    m.control = std::move(controller);
    return m;
  }
  for (ActuatedJoint& a : m.actuated) {
    const ShaperSpec& sh = a.control.shaper;
    const ShaperKind kind = parse_shaper_kind(sh.type);
    a.shaper = {Impulse{0.0, 1.0}};
    if (kind != ShaperKind::kNone) {
      double w = sh.frequency, z = sh.damping;
      if (w == 0.0) {
        if (m.resonances.empty())
          throw ConfigError(src, 0, joint_key(a, "shaper.frequency"), "the closed loop has no resonance to design on; give frequency");
        w = m.resonances[0];
        if (z < 0.0) z = zetas[0];
      }
      if (z < 0.0) z = 0.0;
      try {
        a.shaper = make_shaper(kind, w, z, sh.vtol);
      } catch (const std::invalid_argument& e) {
        throw ConfigError(src, 0, joint_key(a, "shaper"), e.what());
      }
    }
    const NotchSpec& n = a.control.notch;
    if (n.enabled) {
      NotchDesign d;
      d.order = n.order;
      for (int i = 0; i < 2; ++i) {
        d.alpha[i] = n.alpha[i];
        d.zeta[i] = n.zeta[i];
        d.omega_z[i] = n.omega_z[i];
      }
      if (d.omega_z[0] == 0.0) {
        if (m.resonances.size() < 2)
          throw ConfigError(src, 0, joint_key(a, "notch.omega_z"),
                            "the closed loop has fewer than two resonances to place the notch at; give omega_z");
        d.omega_z[0] = m.resonances[0];
        d.omega_z[1] = m.resonances[1];
      }
      try {
        a.notch = make_notch_sections(d, m.control_period);
      } catch (const std::invalid_argument& e) {
        throw ConfigError(src, 0, joint_key(a, "notch"), e.what());
      }
    }
  }
  return m;
}

bool parse_monitor_type(const std::string& name, MonitorType& out) {
  static const std::pair<const char*, MonitorType> types[] = {
      {"joint_torque", MonitorType::kJointTorque}, {"joint_speed", MonitorType::kJointSpeed},
      {"deflection", MonitorType::kDeflection},    {"tool_speed", MonitorType::kToolSpeed},
      {"workspace", MonitorType::kWorkspace},      {"clearance", MonitorType::kClearance},
      {"command", MonitorType::kCommand}};
  for (const auto& [n, t] : types)
    if (name == n) return out = t, true;
  return false;
}

bool parse_monitor_action(const std::string& name, MonitorAction& out) {
  static const std::pair<const char*, MonitorAction> actions[] = {{"record", MonitorAction::kRecord},
                                                                  {"hold", MonitorAction::kHold},
                                                                  {"stop", MonitorAction::kStop},
                                                                  {"brake", MonitorAction::kBrake}};
  for (const auto& [n, a] : actions)
    if (name == n) return out = a, true;
  return false;
}

StaticEquilibriumResult calc_arm_sag(const ArmModel& m, const Eigen::VectorXd& pose) {
  StaticEquilibriumOptions held;
  std::vector<char> elastic(static_cast<std::size_t>(m.tree.nv()), 0);
  for (int d : m.compliant_dofs) elastic[static_cast<std::size_t>(d)] = 1;
  for (int j = 0; j < m.tree.nv(); ++j)
    if (!elastic[static_cast<std::size_t>(j)]) held.locked_dofs.push_back(j);
  StaticEquilibriumResult r = solve_static_equilibrium(m.tree, pose, Eigen::VectorXd::Zero(m.tree.nv()), held);
  if (!r.converged()) r.q = pose;  // a link that buckles under its weight: it starts straight
  // A true sag lowers the mass centre (the springs' energy comes from gravity's): one that rose is a
  // spurious equilibrium of links far too soft for their load.
  TreeWorkspace ws(m.tree);
  double mass = 0.0;
  for (int i = 0; i < m.tree.num_bodies(); ++i) mass += m.tree.body(i).mass;
  const double rise = (calc_potential_energy(m.tree, r.q, ws) - calc_potential_energy(m.tree, pose, ws)) /
                      (mass * m.tree.gravity().norm());  // m
  if (rise > 1e-6)
    throw ConfigError(m.spec.source, 0, "", "the static sag under gravity moved the arm's mass centre up by " +
                                                format_key_number(1e3 * rise) + " mm, against gravity: links far too soft "
                                                "for their load; check the flexible links' E and G (Pa, not GPa) and density (kg/m³)");
  return r;
}

std::pair<double, double> calc_initial_pressures(const ActuatedJoint& a) {
  const HydraulicSpec& h = a.control.hydraulics;
  const double mean = 0.5 * (h.supply_pressure + h.tank_pressure), half = 0.5 * a.hold_torque / calc_displacement(h);
  return {mean + half, mean - half};
}

void eval_arm_reference(const ArmModel& m, double t, double* r, double* rd, double* rdd, double* scratch) {
  const std::size_t na = m.actuated.size();
  double* q = scratch;
  double* qd = scratch + na;
  double* qdd = scratch + 2 * na;
  for (std::size_t j = 0; j < na; ++j) r[j] = rd[j] = rdd[j] = 0.0;
  if (m.trajectory.waypoints.empty()) {
    for (std::size_t j = 0; j < na; ++j) r[j] = m.trajectory.start[j];
    return;
  }
  // Each joint's shaper: the sum of the trajectory delayed by each impulse, weighted.
  for (std::size_t j = 0; j < na; ++j) {
    for (const Impulse& imp : m.actuated[j].shaper) {
      eval_joint_trajectory(m.trajectory, t - imp.time, q, qd, qdd);
      r[j] += imp.amplitude * q[j];
      rd[j] += imp.amplitude * qd[j];
      rdd[j] += imp.amplitude * qdd[j];
    }
  }
}

ArmFeedforward::ArmFeedforward(const Tree& tree)
    : ws(tree),
      q(Eigen::VectorXd::Zero(tree.nv())),
      qd(Eigen::VectorXd::Zero(tree.nv())),
      qdd(Eigen::VectorXd::Zero(tree.nv())),
      tau(Eigen::VectorXd::Zero(tree.nv())),
      zero(Eigen::VectorXd::Zero(tree.nv())) {}

void calc_arm_feedforward(const ArmModel& m, const double* r, const double* rd, const double* rdd, double* tau_id,
                          double* tau_g, ArmFeedforward& ff) {
  ff.q.setZero();
  ff.qd.setZero();
  ff.qdd.setZero();
  const std::size_t na = m.actuated.size();
  for (std::size_t j = 0; j < na; ++j) {
    const int d = m.actuated[j].dof;
    ff.q[d] = r[j];
    ff.qd[d] = rd[j];
    ff.qdd[d] = rdd[j];
  }
  calc_inverse_dynamics(m.tree, ff.q, ff.qd, ff.qdd, ff.tau, ff.ws);
  // The joint's own passive spring and damper (BodySpec) are part of what its drive must supply.
  for (std::size_t j = 0; j < na; ++j) {
    const Body& b = m.tree.body(m.actuated[j].body);
    tau_id[j] = ff.tau[m.actuated[j].dof] + b.stiffness * (r[j] - b.spring_reference) + b.damping * rd[j];
  }
  calc_bias_forces(m.tree, ff.q, ff.zero, ff.tau, ff.ws);
  for (std::size_t j = 0; j < na; ++j) tau_g[j] = ff.tau[m.actuated[j].dof];
}

}  // namespace ff
