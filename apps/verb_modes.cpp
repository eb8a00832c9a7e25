// flexfarm modes MODEL: natural frequencies and damping. A flexfarm model (configs/fbtb.yaml): clamped
// and in the closed loop. A kinematic tree (URDF or tree YAML, description/load.hpp): linearised at a
// pose, chosen joints locked, the mode shapes optionally to CSV.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "apps/verbs.hpp"
#include "description/load.hpp"
#include "common/closest.hpp"
#include "common/units_check.hpp"
#include "common/errors.hpp"
#include "common/files.hpp"
#include "kernel/modes.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/modes.hpp"
#include "arm/arm_model.hpp"

namespace ff {

namespace {

void print_modes(const char* title, const std::vector<Mode>& modes, int count) {
  print_safe(stdout, "%s\n  %-4s %12s %12s %10s\n", title, "mode", "f (Hz)", "omega (rad/s)", "zeta");
  int shown = 0;
  for (const auto& m : modes) {
    if (shown++ == count) break;
    if (m.oscillatory)
      print_safe(stdout, "  %-4d %12.4f %12.4f %10.4f\n", shown, m.frequency_hz(), m.omega_n, m.zeta);
    else if (m.omega_n == 0.0)
      print_safe(stdout, "  %-4d %12s %12s %10s   free: nothing resists this motion\n", shown, "-", "0", "-");
    else
      print_safe(stdout, "  %-4d %12s %12.4f %10s   real pole, time constant %.4g s\n", shown, "-", m.omega_n, "-",
                  1.0 / m.omega_n);
  }
}

// The dof of a joint named on the command line; a ConfigError naming the option otherwise.
int dof_of(const TreeDescription& d, const std::string& name, const std::string& option) {
  const auto it = d.dof_index.find(name);
  if (it != d.dof_index.end()) return it->second;
  const std::vector<std::string> names = list_joint_names(d);
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  throw ConfigError(option, 0, name, "no moving joint of that name" + format_did_you_mean(name, names) + " (joints: " + known + ")");
}

// The pose --at JOINT=VALUE sets (on top of `q0`); with `check_units` (the arm model's `units_check`) a
// revolute joint's value beyond a turn is refused as degrees.
Eigen::VectorXd parse_pose(const TreeDescription& d, Eigen::VectorXd q0, const std::vector<std::string>& at,
                           bool check_units) {
  for (const std::string& a : at) {
    const auto eq = a.find('=');
    if (eq == std::string::npos) throw ConfigError("--at", 0, a, "expected JOINT=VALUE");
    const std::string name = a.substr(0, eq);
    const int j = dof_of(d, name, "--at");
    const auto value = parse_finite(std::string_view(a).substr(eq + 1));
    if (!value) throw ConfigError("--at", 0, a, "expected a finite number after '=' (rad or m)");
    q0[j] = *value;
    for (std::size_t i = 0; i < d.joints.size() && check_units; ++i)
      if (d.joints[i].name == name && d.spec.bodies[i].joint == JointType::kRevolute && !explain_angle_unit(q0[j]).empty())
        throw ConfigError("--at", 0, name, explain_angle_unit(q0[j]));
  }
  return q0;
}

// One table of linearised modes.
void print_tree_modes(const char* title, const std::vector<TreeMode>& modes, int count) {
  // A mode of omega 0 (round-off of zero, multibody/modes.hpp) is motion nothing resists.
  print_safe(stdout, "%s\n  %-4s %12s %12s %10s\n", title, "mode", "f (Hz)", "omega (rad/s)", "zeta");
  // A mode that moves no joint and that nothing restores (a hydraulic actuator's mean chamber pressure)
  // is counted below the table, not listed.
  const auto still = [&](const TreeMode& m) { return !m.moves && m.omega_n == 0.0; };
  int listed = 0, neutral = 0;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const TreeMode& m = modes[k];
    if (still(m)) {
      ++neutral;
      continue;
    }
    if (++listed > count) continue;
    if (m.oscillatory)
      print_safe(stdout, "  %-4zu %12.4f %12.4f %10.4f\n", static_cast<std::size_t>(listed), m.frequency_hz(), m.omega_n, m.zeta);
    else if (m.omega_n == 0.0)
      print_safe(stdout, "  %-4zu %12s %12s %10s   free: nothing resists this motion\n", static_cast<std::size_t>(listed), "-", "0", "-");
    else if (m.zeta < 0.0)
      print_safe(stdout, "  %-4zu %12s %12.4f %10s   unstable: grows e-fold in %.4g s\n", static_cast<std::size_t>(listed), "-", m.omega_n, "-",
                  1.0 / m.omega_n);
    else
      print_safe(stdout, "  %-4zu %12s %12.4f %10s   real pole, time constant %.4g s\n", static_cast<std::size_t>(listed), "-", m.omega_n, "-",
                  1.0 / m.omega_n);
  }
  if (neutral > 0)
    print_safe(stdout, "  and %d neutral state%s that move%s no joint (omega 0; the hydraulic actuators' mean chamber "
                "pressures, which the linearised valves do not restore)\n",
                neutral, neutral == 1 ? "" : "s", neutral == 1 ? "s" : "");
}

// One row per mode: its frequency, damping and the joint coordinates of its shape.
void write_mode_shapes(const TreeDescription& d, const std::vector<TreeMode>& modes, int nv, const std::string& path) {
  std::vector<std::string> names(static_cast<std::size_t>(nv));
  for (const auto& [n, j] : d.dof_index) names[static_cast<std::size_t>(j)] = n;
  std::ostringstream out;
  out.precision(10);
  out << "mode,omega_rad_s,frequency_hz,zeta,oscillatory";
  for (const std::string& n : names) out << ',' << n;
  out << '\n';
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const TreeMode& m = modes[k];
    out << k + 1 << ',' << m.omega_n << ',' << m.frequency_hz() << ',' << m.zeta << ',' << (m.oscillatory ? 1 : 0);
    for (int j = 0; j < nv; ++j) out << ',' << m.shape[j];
    out << '\n';
  }
  write_file_atomic(path, out.str());
  print_safe(stdout, "mode shapes: %s\n", path.c_str());
}

struct ModesOptions {
  std::vector<std::string> at, lock;
  int count = 6;
  std::string shapes;
  bool statics = false;
};

void print_tree_header(const std::string& path, const Tree& tree, std::size_t locked) {
  print_safe(stdout, "tree %s: %d bodies, %d moving joints (%zu locked), gravity (%.4g, %.4g, %.4g) m/s^2\n", path.c_str(),
              tree.num_bodies(), tree.nv(), locked, tree.gravity()[0], tree.gravity()[1], tree.gravity()[2]);
}

// Modes of a URDF at a pose (--at JOINT=VALUE, the rest at 0), --lock JOINT held.
void urdf_modes(const std::string& path, const std::string& sidecar, const ModesOptions& o) {
  const TreeDescription d = load_tree_description(path, sidecar);
  const Tree tree = make_tree(d.spec);
  const Eigen::VectorXd q0 = parse_pose(d, Eigen::VectorXd::Zero(tree.nv()), o.at, false);  // a URDF's values unchecked
  TreeModeOptions options;
  for (const std::string& name : o.lock) options.locked_dofs.push_back(dof_of(d, name, "--lock"));
  const std::vector<TreeMode> modes = calc_tree_modes(tree, q0, options);
  print_tree_header(path, tree, options.locked_dofs.size());
  print_tree_modes("linearised modes:", modes, o.count);
  if (!o.shapes.empty()) write_mode_shapes(d, modes, tree.nv(), o.shapes);
}

// Modes of an arm model (or a tree YAML) at a pose: its joints there (--at, else the start), its
// flexible links at their static sag under gravity. Without actuated joints: the tree's modes
// (--lock held). With them: clamped (the actuated joints locked too) and in the closed loop (their PD
// gains added); --static prints the sag of each link tip and of the tool.
void arm_modes(const std::string& path, const std::vector<std::string>& sets, const ModesOptions& o) {
  const ArmModel arm = load_arm_with(path, sets);
  const TreeDescription& d = arm.spec.tree;
  const Tree& tree = arm.tree;
  const int nv = tree.nv();
  Eigen::VectorXd start = arm.q0;
  for (int j : arm.compliant_dofs) start[j] = 0.0;
  const StaticEquilibriumResult sag = calc_arm_sag(arm, parse_pose(d, start, o.at, arm.spec.units_check));
  if (!sag.converged()) print_safe(stdout, "static sag not found (%s): linearised at the straight links\n", sag.message.c_str());
  const Eigen::VectorXd& q0 = sag.q;
  TreeModeOptions options;
  for (const std::string& name : o.lock) options.locked_dofs.push_back(dof_of(d, name, "--lock"));
  print_tree_header(path, tree, options.locked_dofs.size());
  std::vector<TreeMode> modes;
  if (arm.actuated.empty()) {
    modes = calc_tree_modes(tree, q0, options);
    print_tree_modes("linearised modes:", modes, o.count);
  } else {
    TreeModeOptions clamped = options;
    for (const ActuatedJoint& a : arm.actuated)
      if (std::find(clamped.locked_dofs.begin(), clamped.locked_dofs.end(), a.dof) == clamped.locked_dofs.end())
        clamped.locked_dofs.push_back(a.dof);
    print_tree_modes("clamped (the actuated joints held):", calc_tree_modes(tree, q0, clamped), o.count);
    // The PD on K and C, each hydraulic actuator's states linearised with it (make_arm_loop_options).
    TreeModeOptions loop = make_arm_loop_options(arm, q0);
    loop.locked_dofs = options.locked_dofs;
    modes = calc_tree_modes(tree, q0, loop);
    bool hydraulic = false;
    for (const ActuatedJoint& a : arm.actuated) hydraulic = hydraulic || a.control.hydraulics.enabled;
    print_tree_modes(hydraulic ? "closed loop (continuous-time PD on the actuated joints, the hydraulic actuators' "
                                 "spool, torque loop and chambers linearised):"
                               : "closed loop (continuous-time PD on the actuated joints):",
                     modes, o.count);
    print_safe(stdout, "fixed-step substeps per control period: %d (h = %.3g ms, %s)\n", arm.substeps,
                1e3 * arm.control_period / arm.substeps, arm.integrator == Integrator::kRk4 ? "rk4" : "implicit");
  }
  if (!o.shapes.empty()) write_mode_shapes(d, modes, nv, o.shapes);
  if (!o.statics) return;
  // The sag: each link tip from its straight position (root frame), and the tool from the rigid arm's.
  std::vector<Pose> poses(static_cast<std::size_t>(tree.num_bodies())), rigid(poses.size());
  calc_body_poses(tree, q0, poses);
  Eigen::VectorXd straight = q0;
  for (int j : arm.compliant_dofs) straight[j] = 0.0;
  calc_body_poses(tree, straight, rigid);
  print_safe(stdout, "static deflection under gravity (%s):\n  %-16s %12s %12s %12s\n",
              sag.converged() ? "converged" : "not converged", "", "dx (mm)", "dy (mm)", "dz (mm)");
  for (const LinkTip& l : arm.links) {
    const Pose& root = poses[static_cast<std::size_t>(l.root_body)];
    const Vec3 d2 = root.rotation.transpose() * (poses[static_cast<std::size_t>(l.tip_body)].point(l.tip_point) - root.position) - l.rigid_tip;
    print_safe(stdout, "  %-16s %12.4f %12.4f %12.4f   (tip, link frame)\n", l.name.c_str(), 1e3 * d2.x(), 1e3 * d2.y(), 1e3 * d2.z());
  }
  for (const ArmTool& t : arm.tools) {
    const Vec3 tool = poses[static_cast<std::size_t>(t.body)].point(t.point) - rigid[static_cast<std::size_t>(t.body)].point(t.point);
    print_safe(stdout, "  %-16s %12.4f %12.4f %12.4f   (base frame; |sag| %.4f mm)\n", t.name.c_str(), 1e3 * tool.x(),
                1e3 * tool.y(), 1e3 * tool.z(), 1e3 * tool.norm());
  }
}

}  // namespace

void add_modes_verb(CLI::App& app) {
  auto* cmd = app.add_subcommand("modes", "Print natural frequencies and damping ratios: of a flexfarm model clamped "
                                          "and in the closed loop (with the equivalent cantilever stiffness 3EI/L), "
                                          "or of a kinematic tree (URDF or tree YAML) linearised at a pose");
  struct Args {
    std::string model;
    std::vector<std::string> sets;
    int count = 6;
    std::string sidecar, shapes;
    std::vector<std::string> at, lock;
    bool statics = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("model", args->model, "model YAML file, e.g. configs/fbtb.yaml")->required()->check(kPath)->check(CLI::ExistingFile);
  cmd->add_option("--set", args->sets, "override a model parameter, PATH=VALUE (e.g. segments=24); repeatable");
  cmd->add_option("--count", args->count, "modes to list per table")->check(CLI::PositiveNumber);
  cmd->add_option("--sidecar", args->sidecar, "tree: a flexfarm sidecar YAML for a URDF (joint springs)")
      ->check(kPath)
      ->check(CLI::ExistingFile);
  cmd->add_option("--at", args->at, "tree: the pose, JOINT=VALUE (rad or m; others 0); repeatable");
  cmd->add_option("--lock", args->lock, "tree: hold this joint still (a clamped joint); repeatable");
  cmd->add_option("--shapes", args->shapes, "tree: write every mode's frequency, damping and shape to this CSV")->check(kPath);
  cmd->add_flag("--static", args->statics, "arm: also print the static deflection under gravity at the pose");
  cmd->callback([args] {
    const ModesOptions o{args->at, args->lock, args->count, args->shapes, args->statics};
    if (is_arm_model_file(args->model)) {
      if (!args->sidecar.empty()) throw ConfigError("--sidecar", 0, "", "an arm model names its sidecar in `sidecar:`");
      return arm_modes(args->model, args->sets, o);
    }
    if (is_tree_description(args->model)) {
      if (!args->sets.empty())
        throw ConfigError("--set", 0, args->sets[0], "a URDF has no parameter paths; write an arm model that names it");
      if (args->statics) throw ConfigError("--static", 0, "", "is for arm models (docs/formats.md)");
      return urdf_modes(args->model, args->sidecar, o);
    }
    if (args->statics) throw ConfigError("--static", 0, "", "is for arm models (the rig's beam has no gravity load)");
    for (const auto* o : {&args->sidecar, &args->shapes})
      if (!o->empty()) throw ConfigError(*o, 0, "", "--sidecar and --shapes are for tree descriptions");
    if (!args->at.empty() || !args->lock.empty())
      throw ConfigError(args->model, 0, "", "--at and --lock are for tree descriptions (URDF or tree YAML)");
    const Model m = load_model_with(args->model, args->sets);
    const auto& b = m.spec.beam;
    if (m.nseg > 1)
      print_safe(stdout, "model %s: N = %d segments, cell l = %.5f m, joint k = %.5g N m/rad, c = %.5g N m s/rad\n",
                  args->model.c_str(), m.nseg, m.cell, m.joint_k[1], m.joint_c[1]);
    else
      print_safe(stdout, "model %s: N = 1, one rigid arm (no joints)\n", args->model.c_str());
    print_safe(stdout, "beam mass %.2f kg, EI = %.5g N m^2\n", calc_beam_mass(b), b.youngs_modulus * calc_area_moment(b));
    print_safe(stdout, "equivalent cantilever stiffness 3EI/L (seed eq. 5):\n");
    print_safe(stdout, "  one cell   (L = %.5f m): %10.2f kN m/rad\n", m.cell, 1e-3 * calc_cantilever_stiffness(b, m.cell));
    print_safe(stdout, "  whole beam (L = %.5f m): %10.2f kN m/rad\n", b.length, 1e-3 * calc_cantilever_stiffness(b, b.length));
    print_modes("clamped hub:", calc_clamped_modes(m), args->count);
    print_modes("closed loop (continuous-time PD on the hub):", calc_closed_loop_modes(m), args->count);
    const auto res = calc_closed_loop_resonances(m);
    if (res.size() >= 2)
      print_safe(stdout, "closed-loop resonances for the notch filter: omega_z1 = %.4f rad/s (%.4f Hz), omega_z2 = %.4f rad/s (%.4f Hz)\n",
                  res[0], res[0] / (2 * 3.141592653589793), res[1], res[1] / (2 * 3.141592653589793));
    print_safe(stdout, "fixed-step substeps per control period: %d (h = %.3g ms)\n", m.substeps,
                1e3 * m.control_period / m.substeps);
  });
}

}  // namespace ff
