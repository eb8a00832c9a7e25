// Arm model files (arm_yaml.hpp). Each block's keys are one field table below.
#include "arm/arm_yaml.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>

#include "description/tree_yaml.hpp"
#include "description/urdf.hpp"
#include "common/closest.hpp"
#include "common/errors.hpp"
#include "kernel/drive.hpp"
#include "kernel/model_io.hpp"
#include "kernel/modes.hpp"  // kMaxSubsteps
#include "world/world_yaml.hpp"

namespace ff {

namespace {

// The top level beyond the tree.
struct TopBlock {
  std::string description, urdf, sidecar;
  Vec3 gravity{0.0, 0.0, -9.81};
};
const std::array<Field<TopBlock>, 4> kTopFields{{
    {.key = "description", .member = &TopBlock::description, .fallback = "\"\""},
    {.key = "urdf", .member = &TopBlock::urdf, .fallback = "none: the tree is `bodies`"},
    {.key = "sidecar", .member = &TopBlock::sidecar, .fallback = "none"},
    {.key = "gravity", .member = &TopBlock::gravity, .unit = "m/s²"},
}};

const std::array<Field<ArmSpec>, 2> kToolFields{{
    {.key = "body", .member = &ArmSpec::tool_body, .fallback = "the last body (a flexible link: its tip)"},
    {.key = "point", .member = &ArmSpec::tool_point, .unit = "m"},
}};

// One of several named tools (`tools: {NAME: {body, point}}`).
const std::array<Field<ToolSpec>, 2> kToolsFields{{
    {.key = "body", .member = &ToolSpec::body, .fallback = "the last body (a flexible link: its tip)"},
    {.key = "point", .member = &ToolSpec::point, .unit = "m"},
}};

const std::array<Field<ArmSpec>, 2> kControllerFields{{
    {.key = "rate", .member = &ArmSpec::rate, .unit = "Hz", .bound = Bound::kPositive},
    {.key = "model", .member = &ArmSpec::controller_model},
}};

const std::array<Field<JointControlSpec>, 6> kGainFields{{
    {.key = "kp", .member = &JointControlSpec::kp, .unit = "N·m/rad (N/m)", .bound = Bound::kNonNegative},
    {.key = "ki", .member = &JointControlSpec::ki, .unit = "N·m/(rad·s)", .bound = Bound::kNonNegative},
    {.key = "kd", .member = &JointControlSpec::kd, .unit = "N·m·s/rad", .bound = Bound::kNonNegative},
    {.key = "torque_limit", .member = &JointControlSpec::torque_limit, .unit = "N·m (N)", .bound = Bound::kNonNegative,
     .fallback = "0: the joint's effort limit, or none"},
    {.key = "feedforward", .member = &JointControlSpec::feedforward, .bound = Bound::kNonNegative},
    {.key = "gravity_compensation", .member = &JointControlSpec::gravity_compensation, .bound = Bound::kNonNegative},
}};

const std::array<Field<NotchSpec>, 3> kNotchFields{{
    {.key = "enabled", .member = &NotchSpec::enabled},
    {.key = "placement", .member = &NotchSpec::placement},
    {.key = "order", .member = &NotchSpec::order, .bound = Bound::kPositive},
}};

const std::array<Field<ShaperSpec>, 4> kShaperFields{{
    {.key = "type", .member = &ShaperSpec::type},
    {.key = "frequency", .member = &ShaperSpec::frequency, .unit = "rad/s", .bound = Bound::kNonNegative,
     .fallback = "0: the arm's first closed-loop resonance"},
    {.key = "damping", .member = &ShaperSpec::damping, .fallback = "-1: that resonance's"},
    {.key = "vtol", .member = &ShaperSpec::vtol, .bound = Bound::kPositive},
}};

// A joint's plant and sensor blocks (the reference rig's hub blocks, per actuated joint).
const std::array<Field<JointControlSpec>, 1> kJointFields{{
    {.key = "torque_offset", .member = &JointControlSpec::torque_offset, .unit = "N·m (N)"},
}};

const std::array<Field<FrictionSpec>, 11> kFrictionFields{{
    {.key = "viscous", .member = &FrictionSpec::viscous, .unit = "N·m·s/rad (N·s/m)", .bound = Bound::kNonNegative},
    {.key = "coulomb", .member = &FrictionSpec::coulomb, .unit = "N·m (N)", .bound = Bound::kNonNegative},
    {.key = "stiction", .member = &FrictionSpec::stiction, .unit = "N·m (N)", .bound = Bound::kNonNegative,
     .fallback = "0: no Stribeck peak"},
    {.key = "stribeck_velocity", .member = &FrictionSpec::stribeck_velocity, .unit = "rad/s (m/s)", .bound = Bound::kPositive},
    {.key = "smoothing", .member = &FrictionSpec::smoothing, .unit = "rad/s (m/s)", .bound = Bound::kPositive},
    {.key = "model", .member = &FrictionSpec::model},
    {.key = "bristle_stiffness", .member = &FrictionSpec::bristle_stiffness, .unit = "N·m/rad (N/m)",
     .bound = Bound::kPositive},
    {.key = "bristle_damping", .member = &FrictionSpec::bristle_damping, .unit = "N·m·s/rad (N·s/m)",
     .bound = Bound::kNonNegative},
    {.key = "position_waves", .member = &FrictionSpec::position_waves, .unit = "1/rev (1/m)",
     .bound = Bound::kNonNegative},
    {.key = "position_cos", .member = &FrictionSpec::position_cos},
    {.key = "position_sin", .member = &FrictionSpec::position_sin},
}};

const std::array<Field<ChannelSpec>, 4> kAngleSensorFields{{
    {.key = "resolution", .member = &ChannelSpec::resolution, .unit = "rad (m)", .bound = Bound::kNonNegative,
     .fallback = "0: none"},
    {.key = "noise", .member = &ChannelSpec::noise, .unit = "rad (m)", .bound = Bound::kNonNegative, .fallback = "0: none"},
    {.key = "delay", .member = &ChannelSpec::delay, .unit = "controller samples", .bound = Bound::kNonNegative},
    {.key = "rate", .member = &ChannelSpec::rate, .unit = "Hz", .bound = Bound::kNonNegative,
     .fallback = "0: controller.rate"},
}};
// A slipped encoder: the angle sensor's fault (a perturbation a safety monitor may catch).
const std::array<Field<JointControlSpec>, 2> kAngleFaultFields{{
    {.key = "fault_time", .member = &JointControlSpec::angle_fault_time, .unit = "s", .bound = Bound::kNonNegative,
     .fallback = "none"},
    {.key = "fault_offset", .member = &JointControlSpec::angle_fault_offset, .unit = "rad (m)"},
}};
const std::array<Field<ChannelSpec>, 4> kRateSensorFields{{
    {.key = "resolution", .member = &ChannelSpec::resolution, .unit = "rad/s (m/s)", .bound = Bound::kNonNegative,
     .fallback = "0: none"},
    {.key = "noise", .member = &ChannelSpec::noise, .unit = "rad/s (m/s)", .bound = Bound::kNonNegative,
     .fallback = "0: none"},
    {.key = "delay", .member = &ChannelSpec::delay, .unit = "controller samples", .bound = Bound::kNonNegative},
    {.key = "rate", .member = &ChannelSpec::rate, .unit = "Hz", .bound = Bound::kNonNegative,
     .fallback = "0: controller.rate"},
}};

// Both sensors: what a record's column of the channel holds (read: what the controller read; true: on time).
const std::array<Field<LoopChannelSpec>, 2> kLoggedFields{{
    {.key = "logged", .member = &LoopChannelSpec::logged},
    {.key = "logged_delay", .member = &LoopChannelSpec::logged_delay, .unit = "controller samples",
     .bound = Bound::kNonNegative},
}};

// A drive train on the joint (description/tree_description.hpp, DriveTrain), output-side units.
const std::array<Field<DriveTrain>, 8> kDriveFields{{
    {.key = "rotor_inertia", .member = &DriveTrain::rotor_inertia, .unit = "kg·m² (kg)", .bound = Bound::kNonNegative},
    {.key = "ratio", .member = &DriveTrain::ratio, .bound = Bound::kPositive},
    {.key = "stiffness", .member = &DriveTrain::stiffness, .unit = "N·m/rad (N/m)", .bound = Bound::kPositive},
    {.key = "damping", .member = &DriveTrain::damping, .unit = "N·m·s/rad (N·s/m)", .bound = Bound::kNonNegative},
    {.key = "cubic_stiffness", .member = &DriveTrain::cubic_stiffness, .unit = "N·m/rad³ (N/m³)",
     .bound = Bound::kNonNegative},
    {.key = "backlash", .member = &DriveTrain::backlash, .unit = "rad (m)", .bound = Bound::kNonNegative,
     .fallback = "0: none"},
    {.key = "efficiency", .member = &DriveTrain::efficiency, .bound = Bound::kPositive},
    {.key = "closing_damping", .member = &DriveTrain::closing_damping},
}};

struct TrajectoryBlock {
  std::string shape = "quintic";
};
const std::array<Field<TrajectoryBlock>, 1> kTrajectoryFields{{
    {.key = "shape", .member = &TrajectoryBlock::shape},
}};
const std::array<Field<ArmWaypoint>, 2> kWaypointFields{{
    {.key = "time", .member = &ArmWaypoint::time, .unit = "s", .required = true, .bound = Bound::kPositive},
    {.key = "tool", .member = &ArmWaypoint::tool, .unit = "m", .fallback = "none: `joints`"},
}};

struct SimulationBlock {
  std::string integrator = "auto";
};
const std::array<Field<ArmSpec>, 6> kSimulationFields{{
    {.key = "duration", .member = &ArmSpec::duration, .unit = "s", .bound = Bound::kNonNegative,
     .fallback = "0: the last waypoint + settle"},
    {.key = "settle", .member = &ArmSpec::settle, .unit = "s", .bound = Bound::kNonNegative},
    {.key = "substeps", .member = &ArmSpec::substeps, .bound = Bound::kNonNegative, .fallback = "0: from the modes"},
    {.key = "rtol", .member = &ArmSpec::rtol, .bound = Bound::kPositive},
    {.key = "atol", .member = &ArmSpec::atol, .bound = Bound::kPositive},
    {.key = "expected_readings", .member = &ArmSpec::expected_readings},
}};
const std::array<Field<SimulationBlock>, 1> kIntegratorFields{{
    {.key = "integrator", .member = &SimulationBlock::integrator,
     .fallback = "auto: sdirk2 with a flexible link, rk4 without"},
}};

const std::array<Field<ArmSpec>, 2> kMetricsFields{{
    {.key = "band", .member = &ArmSpec::band, .bound = Bound::kPositive},
    {.key = "tool_band", .member = &ArmSpec::tool_band, .unit = "m", .bound = Bound::kNonNegative,
     .fallback = "0: band x the tool's largest move"},
}};

// A part's collision override (`collision: {NAME: {radius, enabled}}`, arm_collision.hpp).
const std::array<Field<CollisionPartSpec>, 2> kCollisionFields{{
    {.key = "radius", .member = &CollisionPartSpec::radius, .unit = "m", .bound = Bound::kNonNegative,
     .fallback = "0: from the geometry"},
    {.key = "enabled", .member = &CollisionPartSpec::enabled},
}};

// A safety monitor (`monitors: {NAME: {type, ...}}`): one table for every type; which keys a type takes
// is monitor_uses / monitor_needs.
const std::array<Field<MonitorSpec>, 12> kMonitorFields{{
    {.key = "type", .member = &MonitorSpec::type, .required = true},
    {.key = "joint", .member = &MonitorSpec::joint, .fallback = "joint_torque, joint_speed: required"},
    {.key = "link", .member = &MonitorSpec::link, .fallback = "deflection: required"},
    {.key = "tool", .member = &MonitorSpec::tool, .fallback = "the first tool"},
    {.key = "limit", .member = &MonitorSpec::limit, .unit = "N·m (N), rad/s (m/s), m/s or m", .bound = Bound::kNonNegative,
     .fallback = "required but by workspace and command"},
    {.key = "lower", .member = &MonitorSpec::lower, .unit = "m", .fallback = "workspace: required"},
    {.key = "upper", .member = &MonitorSpec::upper, .unit = "m", .fallback = "workspace: required"},
    {.key = "time", .member = &MonitorSpec::time, .unit = "s", .bound = Bound::kNonNegative, .fallback = "command: required"},
    {.key = "action", .member = &MonitorSpec::action},
    {.key = "deceleration", .member = &MonitorSpec::deceleration, .unit = "rad/s² (m/s²)", .bound = Bound::kPositive,
     .fallback = "stop: required"},
    {.key = "delay", .member = &MonitorSpec::delay, .unit = "s", .bound = Bound::kNonNegative},
    {.key = "brake_torque", .member = &MonitorSpec::brake_torque, .unit = "N·m (N)", .bound = Bound::kNonNegative,
     .fallback = "0: each joint's torque limit"},
}};

// Which keys a monitor of `type` with `action` takes, and which it must have.
bool monitor_uses(const std::string& type, const std::string& action, const std::string& key) {
  if (key == "type" || key == "action" || key == "delay") return true;
  if (key == "deceleration") return action == "stop";
  if (key == "brake_torque") return action == "brake";
  if (type == "joint_torque" || type == "joint_speed") return key == "joint" || key == "limit";
  if (type == "deflection") return key == "link" || key == "limit";
  if (type == "tool_speed") return key == "tool" || key == "limit";
  if (type == "workspace") return key == "tool" || key == "lower" || key == "upper";
  if (type == "clearance") return key == "limit";
  return key == "time";  // command
}
bool monitor_needs(const std::string& type, const std::string& action, const std::string& key) {
  return key != "tool" && key != "action" && key != "delay" && key != "brake_torque" &&
         (key != "deceleration" || action == "stop") && monitor_uses(type, action, key);
}

std::vector<MonitorSpec> read_monitors(YamlReader& top) {
  std::vector<MonitorSpec> out;
  for (auto& [name, one] : top.named_blocks("monitors", "a map from monitor name to its {type, limit, action, ...}",
                                            "a monitor's name heads its column (NAME.tripped) and metric "
                                            "(NAME_trip_s): no dots, spaces, commas or quotes")) {
    MonitorSpec s;
    s.name = name;
    s.line = one.line();
    only_keys(one, kMonitorFields);
    if (!one.has("type")) one.fail_missing("type", std::string("missing required value (") + kMonitorTypes + ")");
    read_present(one, kMonitorFields, s);
    MonitorType type;
    MonitorAction action;
    if (!parse_monitor_type(s.type, type)) one.fail("type", "unknown monitor type '" + s.type + "' (" + kMonitorTypes + ")");
    if (!parse_monitor_action(s.action, action))
      one.fail("action", "unknown action '" + s.action + "' (record, hold, stop, brake)");
    for (const auto& f : kMonitorFields) {
      if (one.has(f.key) && !monitor_uses(s.type, s.action, f.key))
        one.fail(f.key, std::string("is not a key of a ") + s.type + " monitor with action " + s.action);
      if (!one.has(f.key) && monitor_needs(s.type, s.action, f.key))
        one.fail(f.key, std::string("missing: a ") + s.type + " monitor" + (f.key == std::string("deceleration") ? " that stops" : "") + " needs it");
    }
    one.finish();
    out.push_back(std::move(s));
  }
  return out;
}

// A map of named blocks of one field table (T has `name` and `line`), in file order.
template <class T, std::size_t N>
std::vector<T> read_named_blocks(YamlReader& top, const std::string& key, const std::string& expected,
                                 const std::array<Field<T>, N>& fields, const char* name_rule = nullptr) {
  std::vector<T> out;
  for (auto& [name, one] : top.named_blocks(key, expected, name_rule)) {
    T t;
    t.name = name;
    t.line = one.line();
    read_present(one, fields, t);
    one.finish();
    out.push_back(std::move(t));
  }
  return out;
}

// `name` under `r` names no moving joint of `tree`: the error lists them and the closest.
[[noreturn]] void fail_no_joint(const YamlReader& r, const std::string& name, const TreeDescription& tree) {
  const std::vector<std::string> names = list_joint_names(tree);
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  r.fail(name, "no moving joint of that name" + format_did_you_mean(name, names) + " (joints: " + known + ")");
}

std::string resolve(const std::string& source, const std::string& path) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return path;
  return (std::filesystem::path(source).parent_path() / path).lexically_normal().string();
}

void read_notch(YamlReader& r, NotchSpec& n) {
  read_present(r, kNotchFields, n);
  // The pairs (one number means both) of sections 1 and 2.
  r.optional_array("alpha", n.alpha, 2);
  r.optional_array("zeta", n.zeta, 2);
  r.optional_array("omega_z", n.omega_z, 2);
  if (n.placement != "reference" && n.placement != "feedback")
    r.fail("placement", "unknown placement '" + n.placement + "' (reference, feedback)");
  if (n.order > 8) r.fail("order", "must be between 1 and 8, got " + std::to_string(n.order));
  for (int i = 0; i < 2; ++i) {
    if (!(n.alpha[i] > 0.0)) r.fail("alpha", "must be > 0");
    if (!(n.zeta[i] > 0.0)) r.fail("zeta", "must be > 0");
    if (n.omega_z[i] < 0.0) r.fail("omega_z", "must be >= 0");
  }
  if ((n.omega_z[0] > 0) != (n.omega_z[1] > 0)) r.fail("omega_z", "give both zero frequencies or neither");
}

void read_shaper(YamlReader& r, ShaperSpec& s) {
  read_present(r, kShaperFields, s);
  if (s.type != "none" && s.type != "zv" && s.type != "zvd" && s.type != "ei")
    r.fail("type", "unknown shaper '" + s.type + "' (none, zv, zvd, ei)");
  if (!(s.damping < 1.0)) r.fail("damping", "must be < 1 (negative = the resonance's)");
  if (!(s.vtol < 0.5)) r.fail("vtol", "must be in (0, 0.5)");
}

TreeDescription read_tree(YamlReader& top, const YAML::Node& doc, const TopBlock& tb, const std::string& source) {
  if (!tb.urdf.empty()) {
    if (top.has("bodies")) top.fail("bodies", "give the tree either as `bodies` or as `urdf`, not both");
    TreeDescription d = load_urdf(resolve(source, tb.urdf), resolve(source, tb.sidecar));
    d.spec.gravity = tb.gravity;
    return d;
  }
  if (!tb.sidecar.empty()) top.fail("sidecar", "a sidecar belongs to a `urdf`");
  if (!top.has("bodies")) top.fail("bodies", "missing: the tree's bodies (or a `urdf`)");
  top.raw("bodies");
  YAML::Node tree;
  if (doc["gravity"]) tree["gravity"] = doc["gravity"];
  if (doc["units_check"]) tree["units_check"] = doc["units_check"];
  tree["bodies"] = doc["bodies"];
  return parse_tree_yaml(tree, source);
}

}  // namespace

bool is_arm_document(const YAML::Node& doc) { return doc && doc.IsMap() && (doc["bodies"] || doc["urdf"]); }

ArmSpec parse_arm_spec(const YAML::Node& doc, const std::string& source) {
  LineMap lines;
  YamlReader top(doc, source, "", &lines);
  if (!doc || !doc.IsMap()) top.fail("bodies", "expected a map with `bodies` or `urdf`");
  ArmSpec s;
  s.source = source;
  top.read_units_check();
  s.units_check = top.units_check();
  TopBlock tb;
  read_present(top, kTopFields, tb);
  s.description = tb.description;
  s.tree = read_tree(top, doc, tb, source);

  YamlReader tool = top.child("tool");
  read_present(tool, kToolFields, s);
  s.tool_point_given = tool.has("point");
  tool.finish();
  // Several tool points by name, instead of `tool`.
  if (top.has("tools") && top.has("tool"))
    top.fail("tools", "give either `tool` (one tool point) or `tools` (several, by name), not both");
  s.tools = read_named_blocks(top, "tools", "a map from tool name to its {body, point}", kToolsFields,
                              "a tool's name heads its columns (NAME.x) and metrics: no dots, spaces, commas or quotes");

  YamlReader controller = top.child("controller");
  read_present(controller, kControllerFields, s);
  if (s.controller_model != "nominal" && s.controller_model != "plant")
    controller.fail("model", "unknown model '" + s.controller_model + "' (nominal, plant)");
  controller.finish();

  // joints: a map from joint name to its control, in file order.
  const YAML::Node joints = top.raw("joints");
  if (joints && !joints.IsMap() && !joints.IsNull()) top.fail("joints", "expected a map from joint name to its control");
  if (joints && joints.IsMap()) {
    YamlReader jr(joints, source, "joints", &lines);
    for (const auto& kv : joints) {
      const std::string name = kv.first.as<std::string>();
      YamlReader one = jr.child(name);
      JointControlSpec c;
      c.joint = name;
      YamlReader gains = one.child("controller");
      read_present(gains, kGainFields, c);
      gains.finish();
      YamlReader notch = one.child("notch");
      read_notch(notch, c.notch);
      notch.finish();
      YamlReader shaper = one.child("shaper");
      read_shaper(shaper, c.shaper);
      shaper.finish();
      read_present(one, kJointFields, c);
      YamlReader friction = one.child("friction");
      read_present(friction, kFrictionFields, c.friction);
      if (c.friction.stiction > 0 && c.friction.stiction < c.friction.coulomb)
        friction.fail("stiction", "must be >= coulomb (or 0 for no Stribeck peak)");
      if (c.friction.model != "static" && c.friction.model != "lugre")
        friction.fail("model", "unknown friction model '" + c.friction.model + "' (static, lugre)");
      if (!(std::hypot(c.friction.position_cos, c.friction.position_sin) < 1.0))
        friction.fail("position_cos", "the Coulomb level's ripple needs position_cos^2 + position_sin^2 < 1 (a level that "
                                      "never reaches zero)");
      if (c.friction.model == "lugre" && !(c.friction.coulomb > 0))
        friction.fail("coulomb", "LuGre friction needs coulomb > 0 (the bristles' steady-state level)");
      friction.finish();
      YamlReader sensors = one.child("sensors");
      YamlReader angle = sensors.child("angle");
      read_present(angle, kAngleSensorFields, static_cast<ChannelSpec&>(c.angle_sensor));
      read_present(angle, kAngleFaultFields, c);
      read_present(angle, kLoggedFields, c.angle_sensor);
      angle.finish();
      YamlReader rate = sensors.child("rate");
      read_present(rate, kRateSensorFields, static_cast<ChannelSpec&>(c.rate_sensor));
      read_present(rate, kLoggedFields, c.rate_sensor);
      rate.finish();
      sensors.finish();
      YamlReader drive = one.child("drive");
      DriveTrain train;
      read_present(drive, kDriveFields, train);
      drive.finish();
      // A hydraulic actuator (the rig's `hydraulics:` keys, one table): on by the block's presence.
      YamlReader hydraulics = one.child("hydraulics");
      read_present(hydraulics, hydraulic_fields(), c.hydraulics);
      check_hydraulic_forms(hydraulics, c.hydraulics);
      c.hydraulics.enabled = one.has("hydraulics");
      if (c.hydraulics.enabled) {
        if (const auto [key, why] = explain_hydraulic_fault(c.hydraulics); !key.empty()) hydraulics.fail(key, why);
        if (one.has("drive"))
          one.fail("hydraulics", "a joint has either a compliant drive train (drive:) or a hydraulic actuator "
                                 "(hydraulics:), not both");
      }
      hydraulics.finish();
      one.finish();
      if (!s.tree.dof_index.count(name)) fail_no_joint(jr, name, s.tree);
      c.drive = one.has("drive");
      s.joints.push_back(c);
      // A compliant drive: the joint's rotor and the twist to its link (insert_drive_train).
      if (one.has("drive")) {
        if (train.efficiency > 1.0) drive.fail("efficiency", "must be in (0, 1], got " + format_key_number(train.efficiency));
        if (const std::string fault = insert_drive_train(s.tree, name, train); !fault.empty()) one.fail("drive", fault);
        s.joints.back().train = train;
      }
    }
    jr.finish();
  }

  YamlReader trajectory = top.child("trajectory");
  TrajectoryBlock trb;
  read_present(trajectory, kTrajectoryFields, trb);
  if (trb.shape == "cubic") s.shape = TrajectoryShape::kCubic;
  else if (trb.shape == "quintic") s.shape = TrajectoryShape::kQuintic;
  else trajectory.fail("shape", "unknown shape '" + trb.shape + "' (cubic, quintic)");
  if (const YAML::Node sv = trajectory.raw("start"); sv) {
    if (!sv.IsMap()) trajectory.fail("start", "expected a map from joint name to its value at t = 0 (rad or m)");
    YamlReader vr(sv, source, trajectory.full_key("start"), &lines);
    s.start_line = vr.line();
    for (const auto& kv : sv) {
      const std::string name = kv.first.as<std::string>();
      double value = 0.0;
      vr.optional(name, value);
      if (!s.tree.dof_index.count(name)) fail_no_joint(vr, name, s.tree);
      s.start.emplace_back(name, value);
    }
    vr.finish();
  }
  std::vector<YamlReader> waypoints = trajectory.sequence("waypoints");
  trajectory.finish();
  double previous = 0.0;
  for (YamlReader& w : waypoints) {
    ArmWaypoint wp;
    wp.line = w.line();
    read_present(w, kWaypointFields, wp);
    wp.cartesian = w.has("tool");
    const YAML::Node tv = w.raw("tools");
    if (tv) {  // several tools' targets by name
      if (!tv.IsMap() || tv.size() == 0) w.fail("tools", "expected a map from tool name to its target [x, y, z] (m)");
      YamlReader vr(tv, source, w.full_key("tools"), &lines);
      for (const auto& kv : tv) {
        const std::string name = kv.first.as<std::string>();
        Vec3 target = Vec3::Zero();
        read_vec3(vr, name, target);
        wp.tools.emplace_back(name, target);
      }
      vr.finish();
    }
    const YAML::Node jv = w.raw("joints");
    if (jv) {
      if (!jv.IsMap()) w.fail("joints", "expected a map from joint name to its value (rad or m)");
      YamlReader vr(jv, source, w.full_key("joints"), &lines);
      for (const auto& kv : jv) {
        const std::string name = kv.first.as<std::string>();
        double value = 0.0;
        vr.optional(name, value);
        wp.joints.emplace_back(name, value);
      }
      vr.finish();
    }
    w.finish();
    require(w, kWaypointFields);
    if (wp.cartesian && jv) w.fail("tool", "a waypoint is either a tool position or joint values, not both");
    if (wp.cartesian && tv) w.fail("tools", "give either `tool` (the one tool's target) or `tools`, not both");
    if (!wp.cartesian && !jv && !tv) w.fail("joints", "missing: the joint values (or a `tool` position, or `tools`)");
    if (!(wp.time > previous)) w.fail("time", "waypoints must be in time order, each after the one before");
    previous = wp.time;
    s.waypoints.push_back(std::move(wp));
  }

  YamlReader sim = top.child("simulation");
  read_present(sim, kSimulationFields, s);
  SimulationBlock sb;
  read_present(sim, kIntegratorFields, sb);
  // The seed: any 64-bit whole number (a study writes each variant's own, up to 2^64 - 1).
  if (const YAML::Node seed = sim.raw("seed"); seed) {
    try {
      if (!seed.IsScalar() || seed.Scalar().empty() || seed.Scalar()[0] == '-') throw YAML::Exception(YAML::Mark(), "");
      s.seed = seed.as<std::uint64_t>();
    } catch (const YAML::Exception&) {
      sim.fail("seed", "must be a whole number >= 0");
    }
  }
  sim.finish();
  s.integrator_given = sb.integrator != "auto";
  bool known = sb.integrator == "auto";
  for (Integrator i : {Integrator::kRk4, Integrator::kMidpoint, Integrator::kSdirk2, Integrator::kCvodeDense,
                       Integrator::kCvodeKlu, Integrator::kCvodeGmres})
    if (sb.integrator == integrator_name(i)) s.integrator = i, known = true;
  if (!known)
    sim.fail("integrator", "unknown integrator '" + sb.integrator +
                               "' (auto, rk4, midpoint, sdirk2, cvode_dense, cvode_klu, cvode_gmres)");
  if (s.substeps > kMaxSubsteps) sim.fail("substeps", "must be between 0 (automatic) and 100000");

  // The world around the arm, and the parts' collision overrides.
  s.world = read_world(top, source);
  s.collision = read_named_blocks(top, "collision", "a map from part name (a body or flexible link) to its {radius, enabled}",
                                  kCollisionFields);
  s.monitors = read_monitors(top);

  YamlReader metrics = top.child("metrics");
  read_present(metrics, kMetricsFields, s);
  metrics.finish();
  if (!(s.band < 1.0)) metrics.fail("band", "must be in (0, 1)");
  top.finish();
  return s;
}

ArmModel parse_arm(const YAML::Node& doc, const std::string& source, std::shared_ptr<const ArmModel> controller) {
  return make_arm(parse_arm_spec(doc, source), std::move(controller));
}

std::vector<KeyDoc> arm_yaml_keys() {
  std::vector<KeyDoc> out;
  add_keys(out, "", kTopFields);
  out.push_back(kUnitsCheckKey);
  add_keys(out, "tool.", kToolFields);
  add_keys(out, "tools.NAME.", kToolsFields);
  add_keys(out, "controller.", kControllerFields);
  add_keys(out, "joints.NAME.controller.", kGainFields);
  add_keys(out, "joints.NAME.notch.", kNotchFields);
  const NotchSpec n{};
  out.push_back({"joints.NAME.notch.alpha", "", "no", "[" + format_key_number(n.alpha[0]) + ", " + format_key_number(n.alpha[1]) + "]"});
  out.push_back({"joints.NAME.notch.zeta", "", "no", "[" + format_key_number(n.zeta[0]) + ", " + format_key_number(n.zeta[1]) + "]"});
  out.push_back({"joints.NAME.notch.omega_z", "rad/s", "no", "[0, 0]: this joint's closed-loop resonances"});
  add_keys(out, "joints.NAME.shaper.", kShaperFields);
  add_keys(out, "joints.NAME.", kJointFields);
  add_keys(out, "joints.NAME.friction.", kFrictionFields);
  add_keys(out, "joints.NAME.sensors.angle.", kAngleSensorFields);
  add_keys(out, "joints.NAME.sensors.angle.", kAngleFaultFields);
  add_keys(out, "joints.NAME.sensors.angle.", kLoggedFields);
  add_keys(out, "joints.NAME.sensors.rate.", kRateSensorFields);
  add_keys(out, "joints.NAME.sensors.rate.", kLoggedFields);
  add_keys(out, "joints.NAME.drive.", kDriveFields);
  add_keys(out, "joints.NAME.hydraulics.", hydraulic_fields());
  add_keys(out, "trajectory.", kTrajectoryFields);
  out.push_back({"trajectory.start", "rad (m)", "no", "every joint at 0"});
  add_keys(out, "trajectory.waypoints[i].", kWaypointFields);
  out.push_back({"trajectory.waypoints[i].tools", "m", "no", "none"});
  out.push_back({"trajectory.waypoints[i].joints", "rad (m)", "no", "none: `tool`"});
  add_keys(out, "simulation.", kSimulationFields);
  add_keys(out, "simulation.", kIntegratorFields);
  out.push_back({"simulation.seed", "", "no", "1"});
  add_keys(out, "metrics.", kMetricsFields);
  const std::vector<KeyDoc> world = world_yaml_keys();
  out.insert(out.end(), world.begin(), world.end());
  add_keys(out, "collision.NAME.", kCollisionFields);
  add_keys(out, "monitors.NAME.", kMonitorFields);
  return out;
}

}  // namespace ff
