#include "validate/arm_diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "arm/arm_simulate.hpp"
#include "common/errors.hpp"
#include "validate/arm_record.hpp"
#include "validate/ledger.hpp"
#include "validate/residuals.hpp"

namespace ff {

namespace {

// A trial needing more substeps than this (and more than 4x the base's) is refused as too stiff.
constexpr int kMaxArmFitSubsteps = 64;

// Arm models as diagnose fits them: each assignment set built on the source, the models grouped by shape
// (explain_arm_shape_mismatch) and each group replayed on the record as the lanes of one run.
class ArmFamily : public FitFamily {
 public:
  ArmFamily(const ModelSource& src, const Record& r, int base_substeps) : src_(src), rec_(r), base_substeps_(base_substeps) {}

  std::vector<Prediction> predict(const std::vector<std::vector<Assignment>>& sets) const override {
    std::vector<Prediction> out(sets.size());
    std::vector<std::optional<ArmModel>> models(sets.size());
    std::vector<std::vector<std::size_t>> groups;
    for (std::size_t i = 0; i < sets.size(); ++i) {
      try {
        ArmModel m = build_arm(src_, sets[i]);
        if (sets[i].empty() || m.substeps <= std::max(kMaxArmFitSubsteps, 4 * base_substeps_)) models[i] = std::move(m);
      } catch (const std::exception&) {  // outside the model's valid range
      }
      if (!models[i]) {
        out[i].ok = false;
        continue;
      }
      auto g = std::find_if(groups.begin(), groups.end(), [&](const std::vector<std::size_t>& members) {
        return explain_arm_shape_mismatch(*models[members.front()], *models[i]).empty();
      });
      if (g == groups.end()) groups.push_back({i});
      else g->push_back(i);
    }
    for (const auto& members : groups) {
      std::vector<ArmModel> lanes;
      for (std::size_t i : members) lanes.push_back(*models[i]);
      const std::vector<ArmReplay> replays = replay_arm_records(lanes, rec_);
      for (std::size_t j = 0; j < members.size(); ++j) {
        Prediction& p = out[members[j]];
        p.ok = replays[j].ok;
        p.channels = replays[j].at_record;
      }
    }
    return out;
  }

 private:
  const ModelSource& src_;
  const Record& rec_;
  int base_substeps_;
};

// What a joint's candidates scale with: its torque and rate on the record. The torque's is the larger of
// the base model's closed-loop torque and the record's: an effect the model lacks may be most of what
// the record's torque holds (a load torque on a wrist the model balances with almost nothing).
EffectScales make_torque_scales(const ArmReplay& replay, const Record& r, const ActuatedJoint& a) {
  EffectScales s;
  s.torque_rms = s.torque_max = 0.0;
  for (const std::vector<double>* tau : {&replay.at_record.at(a.name + ".torque"), r.has(a.name + ".torque") ? &r.at(a.name + ".torque") : nullptr}) {
    if (!tau) continue;
    s.torque_rms = std::max(s.torque_rms, calc_rms(*tau));
    for (double x : *tau) s.torque_max = std::max(s.torque_max, std::abs(x));
  }
  s.rate_rms = calc_rms(r.has(a.name + ".rate") ? r.at(a.name + ".rate") : time_derivative(r.t, r.at(a.name + ".angle")));
  return s;
}

// The diagonal of the arm's mass matrix at its start, kg m^2 (kg): each joint's inertia, what its drive's
// and armature's candidates scale with.
Eigen::VectorXd calc_start_inertia(const ArmModel& base) {
  TreeWorkspace ws(base.tree);
  Eigen::MatrixXd M(base.tree.nv(), base.tree.nv());
  calc_mass_matrix(base.tree, base.q0, M, ws);
  return M.diagonal();
}

// The inline tree's body entry named `name` (tree YAML `bodies`), or a null node.
YAML::Node find_body(const YAML::Node& doc, const std::string& name) {
  if (!doc["bodies"] || !doc["bodies"].IsSequence()) return YAML::Node();
  for (const auto& b : doc["bodies"])
    if (b["name"] && b["name"].as<std::string>() == name) return b;
  return YAML::Node();
}

// The inline tree's body whose joint is `joint`, or "".
std::string body_of_joint(const YAML::Node& doc, const std::string& joint) {
  if (!doc["bodies"] || !doc["bodies"].IsSequence()) return "";
  for (const auto& b : doc["bodies"])
    if (b["joint"] && b["joint"]["name"] && b["joint"]["name"].as<std::string>() == joint && b["name"])
      return b["name"].as<std::string>();
  return "";
}

double number_at(const YAML::Node& doc, const std::string& path, double fallback) {
  const YAML::Node v = get_path(doc, path);
  try {
    return v && v.IsScalar() ? v.as<double>() : fallback;
  } catch (const YAML::Exception&) {
    return fallback;
  }
}

std::vector<Effect> make_joint_effects(const ArmModel& base, const YAML::Node& doc, const ActuatedJoint& a,
                                       const EffectScales& sc, double inertia) {
  const std::string j = "joints." + a.name + ".";
  const double tau = std::max(sc.torque_rms, 1e-6), w = std::max(sc.rate_rms, 1e-6);
  const double peak = std::max(sc.torque_max, 1e-6), kp = std::max(a.control.kp, 1e-6);
  const FrictionSpec& f = a.control.friction;
  std::vector<Effect> out;
  const EffectParam coulomb = make_positive_param(j + "friction.coulomb", f.coulomb, 0.05 * tau, 1e-3 * tau, 2.0 * tau);
  // The tanh smoothing from 1e-4 to 1e-2 of the joint's RMS rate, and up to twice the model's own: on a
  // slow joint 1e-2 of the rate is below the default 1e-3 rad/s (the Titan arm's elbow: 5.3e-4), and a
  // fit pinned there misses the friction (14.1 N m for a hidden 15).
  const EffectParam smoothing =
      make_positive_param(j + "friction.smoothing", f.smoothing, 1e-3, 1e-4 * w, std::max(1e-2 * w, 2.0 * f.smoothing));
  out.push_back({"coulomb_friction@" + a.name, "Coulomb friction at " + a.name, {}, {coulomb, smoothing}, "", {}, false, ""});
  out.push_back(make_worn_gear_effect("worn_gear_friction@" + a.name, j + "friction.", "coulomb_friction@" + a.name, f,
                                      coulomb, smoothing));
  out.push_back({"viscous_friction@" + a.name, "viscous friction at " + a.name, {},
                 {make_positive_param(j + "friction.viscous", f.viscous, 0.05 * tau / w, 1e-4 * tau / w, 10.0 * tau / w)},
                 "", {}, false, ""});
  const EffectParam stiction =
      make_positive_param(j + "friction.stiction", f.stiction, std::max(0.1 * tau, 2.0 * f.coulomb), 2e-3 * tau, 4.0 * tau);
  const EffectParam stribeck_velocity =
      make_positive_param(j + "friction.stribeck_velocity", f.stribeck_velocity, 0.05 * w, 1e-3 * w, w);
  out.push_back({"stribeck_friction@" + a.name, "Coulomb friction with a Stribeck (stiction) peak at " + a.name, {},
                 {coulomb, stiction, stribeck_velocity, smoothing}, "", {}, false, "coulomb_friction@" + a.name});
  out.push_back({"lugre_friction@" + a.name, "LuGre friction at " + a.name + ": the Stribeck curve with pre-sliding bristles",
                 {{j + "friction.model", "lugre"}},
                 make_lugre_params(j + "friction.", f, tau, inertia, {coulomb, stiction, stribeck_velocity}), "", {}, false,
                 "stribeck_friction@" + a.name});
  out.push_back({"torque_offset@" + a.name, "a constant load torque on " + a.name + " (cable drag, an unbalanced axis)",
                 {}, {make_effect_param(j + "torque_offset", a.control.torque_offset, sc)}, "", {}, false, ""});
  // The drive train: its spring from the loop's own to a thousand times it, its damper's time constant
  // c/k from 1e-6 to 0.1 s, the rotor from a thousandth of the joint's inertia to all of it. (Not on a
  // hydraulic joint: the two do not go together.)
  const HydraulicSpec& hyd = a.control.hydraulics;
  const double k0 = number_at(doc, j + "drive.stiffness", 200.0 * kp);
  // Free play in that drive (the rig's backlash, per joint): 10 urad to 30 mrad, with the drive's own
  // three fitted beside it; it extends the compliant drive.
  if (!hyd.enabled) {
    const std::vector<EffectParam> drive{
        make_positive_param(j + "drive.stiffness", k0, 200.0 * kp, kp, 1e3 * kp),
        make_positive_param(j + "drive.damping", number_at(doc, j + "drive.damping", 0.0), 1e-3 * k0, 1e-6 * kp, 1e2 * kp),
        make_positive_param(j + "drive.rotor_inertia", number_at(doc, j + "drive.rotor_inertia", 0.0), 0.1 * inertia,
                            1e-3 * inertia, inertia)};
    out.push_back({"drive_compliance@" + a.name, "a compliant drive train between " + a.name + "'s actuator and its link",
                   {}, drive, "", {}, false, ""});
    std::vector<EffectParam> play{make_positive_param(j + "drive.backlash", number_at(doc, j + "drive.backlash", 0.0), 1e-3,
                                                      1e-5, 3e-2)};
    play.insert(play.end(), drive.begin(), drive.end());
    out.push_back({"backlash@" + a.name, "free play in " + a.name + "'s drive train", {}, play, "", {}, false,
                   "drive_compliance@" + a.name});
    out.push_back({"impact_backlash@" + a.name, "free play in " + a.name + "'s drive train, its mesh damping only as the teeth close",
                   {{j + "drive.closing_damping", "true"}}, play, "", {}, false, "backlash@" + a.name});
    std::vector<EffectParam> hardening = drive;
    hardening.push_back(make_cubic_param(j + "drive.cubic_stiffness", number_at(doc, j + "drive.cubic_stiffness", 0.0),
                                         drive[0].initial, peak));
    out.push_back({"mesh_hardening@" + a.name, "a drive train at " + a.name + " whose mesh stiffens with its twist (k e + k3 e^3)",
                   {}, hardening, "", {}, false, "drive_compliance@" + a.name});
  }
  // A hydraulic joint's oil spring 4 beta D^2 / V (the rig's hydraulic_compressibility): the bulk modulus
  // (entrained air lowers it by decades) and the chamber volume.
  if (hyd.enabled)
    out.push_back({"hydraulic_compressibility@" + a.name, "oil compressibility of " + a.name + "'s hydraulic actuator",
                   {},
                   {make_positive_param(j + "hydraulics.bulk_modulus", 0.5 * hyd.bulk_modulus, 0.5 * hyd.bulk_modulus, 1e7, 2e9),
                    make_positive_param(j + "hydraulics.chamber_volume", hyd.chamber_volume, hyd.chamber_volume,
                                        0.1 * hyd.chamber_volume, 10.0 * hyd.chamber_volume)},
                   "", {}, false, ""});
  out.push_back({"torque_saturation@" + a.name, "saturation of " + a.name + "'s actuator torque", {},
                 {make_positive_param(j + "controller.torque_limit", 0.0, 0.8 * peak, 0.05 * peak, 1.5 * peak)}, "", {},
                 false, ""});
  const int last = std::max(24, static_cast<int>(std::ceil(kMaxSearchedDelay * base.spec.rate)));
  out.push_back({"sensor_delay." + a.name + "_angle", "delay of " + a.name + "'s angle measurement (in the loop)", {}, {},
                 j + "sensors.angle.delay", make_delay_grid(last), true, ""});
  if (a.control.kd > 0)
    out.push_back({"sensor_delay." + a.name + "_rate", "delay of " + a.name + "'s rate measurement (in the loop)", {}, {},
                   j + "sensors.rate.delay", make_delay_grid(last), true, ""});
  // The angle late in the loop with its column logged on time (the rig's loop_delay.hub_angle), offered where
  // the model says the column is as read.
  if (!is_logged_on_time(a.control.angle_sensor))
    out.push_back({"loop_delay." + a.name + "_angle", "delay of " + a.name + "'s angle in the loop only, its column logged on time",
                   {{j + "sensors.angle.logged", "true"}}, {}, j + "sensors.angle.delay", make_delay_grid(last), true, ""});
  // A logger that stamps the on-time angle late (logged: true): the scored column shifted, the loop untouched.
  if (is_logged_on_time(a.control.angle_sensor))
    out.push_back({"logger_delay." + a.name + "_angle", "latency of the logged " + a.name + " angle (output only)", {}, {},
                   j + "sensors.angle.logged_delay", make_delay_grid(last), true, ""});
  if (base.tree.body(a.body).joint == JointType::kRevolute)
    out.push_back({"sensor_quantization@" + a.name, "quantisation of " + a.name + "'s angle encoder", {}, {},
                   j + "sensors.angle.resolution", make_encoder_quanta(), false, ""});
  // The joint's armature (a re-fit): only where the tree is inline, so that a path reaches it.
  if (const std::string body = body_of_joint(doc, a.name); !body.empty()) {
    const std::string path = "bodies[" + body + "].joint.armature";
    const double now = number_at(doc, path, 0.0);
    const double lo = now > 0 ? now / 10.0 : 1e-3 * inertia, hi = now > 0 ? now * 30.0 : inertia;
    out.push_back({"armature@" + a.name, a.name + "'s rotor inertia (armature; a re-fit, no new physics)", {},
                   {make_positive_param(path, now, 0.1 * inertia, lo, hi)}, "", {}, false, ""});
  }
  return out;
}

std::vector<Effect> make_link_effects(const YAML::Node& doc, const std::string& link) {
  const std::string b = "bodies[" + link + "].flexible.";
  std::vector<Effect> out;
  out.push_back({"link_stiffness@" + link, link + "'s bending and torsion stiffness (E I, G J; a re-fit)", {},
                 {make_positive_param(b + "stiffness_factor", number_at(doc, b + "stiffness_factor", 1.0), 1.0, 0.2, 5.0)},
                 "", {}, false, ""});
  out.push_back({"link_damping@" + link, "structural damping of " + link + " (c = beta k)", {},
                 {make_positive_param(b + "damping_time", number_at(doc, b + "damping_time", 0.0), 1e-4, 1e-6, 0.1)}, "",
                 {}, false, ""});
  const int n = static_cast<int>(number_at(doc, b + "segments", 6.0));
  out.push_back({"extra_mode@" + link, "more segments in " + link + ": a mode the model lacks", {}, {}, b + "segments",
                 {static_cast<double>(n + 1), static_cast<double>(2 * n)}, false, ""});
  if (const double m = number_at(doc, b + "payload.mass", 0.0); m > 0)
    out.push_back({"payload@" + link, "the payload at " + link + "'s tip (a re-fit, no new physics)", {},
                   {{b + "payload.mass", m, m / 10.0, m * 10.0}}, "", {}, false, ""});
  return out;
}

// The record's scored channels for the model: arm_scored_columns it has and does not hold constant.
std::vector<std::pair<std::string, std::string>> scored_arm_channels(const ArmModel& m, const Record& r) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& [c, joint] : arm_scored_columns(m))
    if (r.has(c) && !is_constant_column(r.at(c))) out.emplace_back(c, joint);
  return out;
}

void check_closed_loop(const DiagnoseOptions& opt) {
  if (opt.mode != ReplayMode::kClosedLoop)
    throw std::invalid_argument(std::string("--mode ") + replay_mode_name(opt.mode) +
                                ": arm models are diagnosed in closed loop only (the record's references drive the "
                                "model's controllers)");
}

std::vector<Effect> make_candidates(const ArmModel& base, const YAML::Node& doc, const Record& r, const ArmReplay& replay) {
  std::vector<Effect> out;
  const Eigen::VectorXd inertia = calc_start_inertia(base);
  for (const ActuatedJoint& a : base.actuated) {
    auto e = make_joint_effects(base, doc, a, make_torque_scales(replay, r, a), inertia[a.dof]);
    out.insert(out.end(), e.begin(), e.end());
  }
  for (const LinkTip& l : base.links)
    if (find_body(doc, l.name)) {
      auto e = make_link_effects(doc, l.name);
      out.insert(out.end(), e.begin(), e.end());
    }
  // A rigid tool body's mass (a re-fit), where the tree is inline: each tool's (`tool:`'s, or `tools:`'s).
  std::vector<std::string> tool_bodies{base.spec.tool_body};
  if (!base.spec.tools.empty()) tool_bodies.clear();
  for (const ToolSpec& t : base.spec.tools)
    if (std::find(tool_bodies.begin(), tool_bodies.end(), t.body) == tool_bodies.end()) tool_bodies.push_back(t.body);
  for (const std::string& tool : tool_bodies)
    if (const YAML::Node b = find_body(doc, tool); b && b["mass"] && !b["flexible"])
      if (const double m = number_at(doc, "bodies[" + tool + "].mass", 0.0); m > 0)
        out.push_back({"payload@" + tool, "the mass of the tool body " + tool + " (a re-fit, no new physics)", {},
                       {{"bodies[" + tool + "].mass", m, m / 10.0, m * 10.0}}, "", {}, false, ""});
  return out;
}

}  // namespace

std::vector<Effect> make_arm_candidate_effects(const ArmModel& base, const YAML::Node& doc, const Record& r) {
  return make_candidates(base, doc, r, replay_arm_record(base, r));
}

Diagnosis diagnose_arm(const ModelSource& src, const Record& r, const DiagnoseOptions& opt) {
  check_closed_loop(opt);
  const ArmModel base = build_arm(src);
  check_arm_record(r, base);
  // The predictions read the sensors' expected values; each joint's encoder and tachometer without noise of
  // their own with the noise that joint's controller read (calc_loop_noise, with_expected_readings).
  std::vector<std::pair<std::string, double>> noise;
  const YAML::Node doc = apply_overrides(src);
  for (const ActuatedJoint& a : base.actuated) {
    auto floor_of = [&](const std::string& column, double none) { return r.has(column) ? calc_noise_floor(r.at(column)) : none; };
    const auto [sa, sr] = calc_loop_noise(floor_of(a.name + ".angle", 0.0), floor_of(a.name + ".rate", 0.0),
                                          floor_of(a.name + ".torque", NAN), a.control.kp, a.control.kd);
    const std::string path = "joints." + a.name + ".sensors.";
    if (number_at(doc, path + "angle.noise", 0.0) == 0.0) noise.emplace_back(path + "angle.noise", sa);
    if (number_at(doc, path + "rate.noise", 0.0) == 0.0) noise.emplace_back(path + "rate.noise", sr);
  }
  const ModelSource fit_src = with_expected_readings(src, noise);
  const ArmFamily family(fit_src, r, base.substeps);
  DiagnoseProblem p;
  p.family = &family;
  p.record = &r;
  p.mode = ReplayMode::kClosedLoop;
  for (const auto& [c, joint] : scored_arm_channels(base, r)) {
    p.channels.push_back(c);
    p.inputs.push_back(r.at((joint.empty() ? base.actuated.front().name : joint) + ".ref"));
  }
  if (p.channels.empty())
    throw ConfigError(r.source, 1, "t", "no column of the record varies: nothing to diagnose");
  for (const ActuatedJoint& a : base.actuated) add_arm_joint_states(r, a.name, false, p.states);
  p.doc = doc;
  const ArmReplay replay = replay_arm_record(base, r);
  p.effects = make_candidates(base, p.doc, r, replay);
  for (const Effect& e : p.effects) p.names.push_back(e.name);
  // Re-fits: each joint's existing friction and offset, each inline joint's armature, each link's damping.
  for (const Effect& e : p.effects)
    for (const auto& q : e.params)
      if (q.path.ends_with("friction.viscous") || q.path.ends_with("friction.coulomb") || q.path.ends_with("torque_offset") ||
          q.path.ends_with("joint.armature") || q.path.ends_with("damping_time"))
        if (std::find_if(p.sensitive.begin(), p.sensitive.end(), [&](const auto& t) { return t.first == q.path; }) ==
            p.sensitive.end())
          p.sensitive.emplace_back(q.path, number_at(p.doc, q.path, 0.0));
  // The ranges of named re-fits: the first joint's torque scales (signed offsets are within twice its torque).
  p.scales = make_torque_scales(replay, r, base.actuated.front());
  return diagnose_problem(p, opt);
}

EffectFit fit_arm_effects(const ModelSource& src, const Record& r, const DiagnoseOptions& opt,
                          const std::vector<std::string>& names) {
  DiagnoseOptions o = opt;
  o.only.clear();
  o.add = names;
  return combine_effects(diagnose_arm(src, r, o).selected);
}

std::string format_calibrated_arm(const ModelSource& src, const EffectFit& fit, const std::string& record_path,
                                  const std::string& out_path) {
  namespace fs = std::filesystem;
  ModelSource rebased{YAML::Clone(src.doc), src.path, src.set};  // (assigning a Node would write through to src's)
  const fs::path from = fs::absolute(src.path).parent_path(), to = fs::absolute(out_path).parent_path();
  for (const char* key : {"urdf", "sidecar"})
    if (rebased.doc[key] && rebased.doc[key].IsScalar()) {
      const fs::path file = rebased.doc[key].as<std::string>();
      if (file.is_absolute()) continue;
      rebased.doc[key] = fs::relative((from / file).lexically_normal(), to).string();
    }
  return format_calibrated_model(rebased, fit, record_path);
}

std::map<std::string, Fit> calc_arm_record_fits(const ArmModel& m, const Record& r) {
  const ArmReplay replay = replay_arm_record(m, r);
  std::map<std::string, Fit> out;
  for (const auto& [c, joint] : scored_arm_channels(m, r))
    out[c] = replay.ok ? calc_fit(r.at(c), replay.at_record.at(c)) : Fit{-INFINITY, INFINITY};
  return out;
}

}  // namespace ff
