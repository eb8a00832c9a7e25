#include "validate/arm_record.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/errors.hpp"
#include "common/random.hpp"
#include "kernel/sensors.hpp"

namespace ff {

namespace {

const char* const kJointSuffixes[] = {".ref", ".angle", ".rate", ".torque"};
const char* const kLinkSuffixes[] = {".deflection_y", ".deflection_z"};

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() > tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

const ActuatedJoint* find_actuated(const ArmModel& m, const std::string& name) {
  for (const ActuatedJoint& a : m.actuated)
    if (a.name == name) return &a;
  return nullptr;
}

bool is_prismatic(const ArmModel& m, int dof) {
  for (int i = 0; i < m.tree.num_bodies(); ++i)
    if (m.tree.body(i).dof == dof) return m.tree.body(i).joint == JointType::kPrismatic;
  return false;
}

std::string joint_list(const ArmModel& m) {
  std::string s;
  for (std::size_t j = 0; j < m.actuated.size(); ++j) s += (j ? ", " : "") + m.actuated[j].name;
  return s;
}

std::string link_list(const ArmModel& m) {
  std::string s;
  for (std::size_t j = 0; j < m.links.size(); ++j) s += (j ? ", " : "") + m.links[j].name;
  return s.empty() ? "none" : s;
}

// A joint's in-loop column (.angle when `angle`, else .rate) of a trace as logged (LoopChannelSpec::logged,
// kernel/sensors.hpp log_channel). noisy: what a record holds (logged as read: the trace's own .q_measured or
// .qd_measured, what the controller read, bit for bit); else the prediction, the controller's reading without
// its noise (the slipped encoder's offset kept) or, on time, the joint's coordinate itself.
std::vector<double> log_arm_column(const ArmTrace& tr, const ArmModel& m, const ActuatedJoint& a, bool angle, bool noisy) {
  const LoopChannelSpec& ch = angle ? a.control.angle_sensor : a.control.rate_sensor;
  const bool read = !is_logged_on_time(ch);
  if (noisy && read) return tr.column(a.name + (angle ? ".q_measured" : ".qd_measured"));
  std::vector<double> y = log_channel(ch, m.spec.rate, angle ? a.angle_key : a.rate_key,
                                      tr.column(a.name + (angle ? ".q" : ".qd")), noisy);
  if (angle && read)  // a slipped encoder, from the first sample at or after its fault time (arm_simulate.cpp)
    for (std::size_t k = 0; k < y.size(); ++k)
      if (static_cast<double>(k) >= a.control.angle_fault_time / m.control_period - 1e-9) y[k] += a.control.angle_fault_offset;
  return y;
}

// The model's column c of a trace: the in-loop ones as logged, the others as the trace has them.
std::vector<double> arm_trace_column(const ArmTrace& tr, const ArmModel& m, const std::string& c, bool noisy) {
  for (const ActuatedJoint& a : m.actuated) {
    if (c == a.name + ".angle") return log_arm_column(tr, m, a, true, noisy);
    if (c == a.name + ".rate") return log_arm_column(tr, m, a, false, noisy);
  }
  return tr.column(arm_trace_name(c));
}

}  // namespace

bool is_arm_record(const Record& r) {
  for (const auto& [name, values] : r.columns)
    if (ends_with(name, ".ref") || ends_with(name, ".angle")) return true;
  return false;
}

std::vector<std::string> arm_record_columns(const ArmModel& m) {
  std::vector<std::string> c;
  for (const ActuatedJoint& a : m.actuated)
    for (const char* s : kJointSuffixes) c.push_back(a.name + s);
  for (const ArmTool& t : m.tools)
    for (const char* s : {".x", ".y", ".z"}) c.push_back(t.name + s);
  for (const LinkTip& l : m.links)
    if (!l.elastic_dofs.empty())  // a one-segment `flexible:` body is rigid: nothing to measure
      for (const char* s : kLinkSuffixes) c.push_back(l.name + s);
  return c;
}

bool is_arm_tool_column(const ArmModel& m, const std::string& column) {
  for (const ArmTool& t : m.tools)
    for (const char* s : {".x", ".y", ".z"})
      if (column == t.name + s) return true;
  return false;
}

std::string arm_record_unit(const ArmModel& m, const std::string& column) {
  for (const ActuatedJoint& a : m.actuated) {
    const bool p = is_prismatic(m, a.dof);
    if (column == a.name + ".ref" || column == a.name + ".angle") return p ? "m" : "rad";
    if (column == a.name + ".rate") return p ? "m/s" : "rad/s";
    if (column == a.name + ".torque") return p ? "N" : "N m";
  }
  for (const std::string& c : arm_record_columns(m))
    if (c == column) return "m";  // the tool and the deflections
  return "";
}

void check_arm_record(const Record& r, const ArmModel& m) {
  // Unknown names first: a misspelt joint is then named as such, not as its missing column.
  for (const auto& [name, values] : r.columns) {
    for (const char* s : kJointSuffixes)
      if (ends_with(name, s)) {
        const std::string joint = name.substr(0, name.size() - std::string(s).size());
        if (!find_actuated(m, joint))
          throw ConfigError(r.source, 1, name,
                            "'" + joint + "' is not an actuated joint of the model (its actuated joints: " +
                                joint_list(m) + ")");
      }
    for (const char* s : kLinkSuffixes)
      if (ends_with(name, s)) {
        const std::string link = name.substr(0, name.size() - std::string(s).size());
        bool known = false;
        for (const LinkTip& l : m.links) known |= l.name == link;
        if (!known)
          throw ConfigError(r.source, 1, name,
                            "'" + link + "' is not a flexible link of the model (its flexible links: " + link_list(m) + ")");
      }
    for (const ArmTool& t : m.tools)
      if (name.rfind(t.name + ".", 0) == 0 && !is_arm_tool_column(m, name))
        throw ConfigError(r.source, 1, name,
                          "unknown tool column (" + t.name + ".x, " + t.name + ".y, " + t.name + ".z: the tool point, base frame, m)");
  }
  const bool arm_form = is_arm_record(r);
  for (const ActuatedJoint& a : m.actuated)
    for (const char* s : {".ref", ".angle"})
      if (!r.has(a.name + s))
        throw ConfigError(r.source, 1, a.name + s,
                          "missing column '" + a.name + s + "', needed for an arm model" +
                              (arm_form ? "" : " (this record is in the reference rig's form: ref, hub_angle, ...)"));
}

std::vector<std::pair<std::string, std::string>> arm_scored_columns(const ArmModel& m) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const ActuatedJoint& a : m.actuated) out.emplace_back(a.name + ".angle", a.name);
  for (const ActuatedJoint& a : m.actuated) out.emplace_back(a.name + ".torque", a.name);
  for (const std::string& c : arm_record_columns(m))
    if (is_arm_tool_column(m, c) || c.find(".deflection_") != std::string::npos) out.emplace_back(c, "");
  return out;
}

void add_arm_joint_states(const Record& r, const std::string& joint, bool torque,
                          std::vector<std::pair<std::string, std::vector<double>>>& s) {
  s.emplace_back(joint + ".velocity", r.has(joint + ".rate") ? r.at(joint + ".rate")
                                                             : time_derivative(r.t, r.at(joint + ".angle")));
  s.emplace_back(joint + ".angle", r.at(joint + ".angle"));
  if (torque && r.has(joint + ".torque")) s.emplace_back(joint + ".torque", r.at(joint + ".torque"));
}

bool is_constant_column(const std::vector<double>& x) {
  for (double v : x)
    if (v != x.front()) return false;
  return true;
}

std::vector<std::vector<double>> sample_arm_reference(const ArmModel& m) {
  const std::size_t na = m.actuated.size();
  const long samples = static_cast<long>(std::floor(m.duration / m.control_period + 1e-9)) + 1;
  std::vector<std::vector<double>> ref(na, std::vector<double>(static_cast<std::size_t>(samples)));
  std::vector<double> r(na), rd(na), rdd(na), scratch(3 * na);
  for (long k = 0; k < samples; ++k) {
    eval_arm_reference(m, static_cast<double>(k) * m.control_period, r.data(), rd.data(), rdd.data(), scratch.data());
    for (std::size_t j = 0; j < na; ++j) ref[j][static_cast<std::size_t>(k)] = r[j];
  }
  return ref;
}

std::string arm_trace_name(const std::string& column) {
  if (ends_with(column, ".angle")) return column.substr(0, column.size() - 6) + ".q";
  if (ends_with(column, ".rate")) return column.substr(0, column.size() - 5) + ".qd";
  return column;
}

Record make_arm_record(const ArmModel& m, const ArmRecordNoise& noise, std::uint64_t seed) {
  const std::vector<std::vector<double>> ref = sample_arm_reference(m);
  ArmRunOptions o;
  o.reference = &ref;
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1), o);
  if (run.status[0] != LaneStatus::kOk) throw std::runtime_error("the model's run failed numerically: no record");
  const ArmTrace& tr = run.traces[0];
  Record r;
  r.source = "<record>";
  r.t = tr.t();
  const std::vector<std::string> cols = arm_record_columns(m);
  for (std::size_t c = 0; c < cols.size(); ++c) {
    std::vector<double> y = arm_trace_column(tr, m, cols[c], true);
    const std::string& n = cols[c];
    const double sd = ends_with(n, ".angle") ? noise.angle
                      : ends_with(n, ".rate") ? noise.rate
                      : ends_with(n, ".torque") ? noise.torque
                      : ends_with(n, ".ref") ? 0.0
                                             : noise.position;
    if (sd > 0.0) {
      CounterRng rng(calc_variant_seed(seed, c + 1));
      for (double& x : y) x += sd * rng.normal();
    }
    r.columns[n] = std::move(y);
  }
  return r;
}

ArmReplaySetup prepare_arm_replay(std::span<const ArmModel> models, const Record& r) {
  const ArmModel& model = models.front();
  const double T = model.control_period;
  const std::size_t n = r.size();
  const double t0 = r.t.front();
  ArmReplaySetup out;
  for (std::size_t k = 0; k < n && !out.resampled; ++k)
    out.resampled = std::abs(r.t[k] - t0 - static_cast<double>(k) * T) > 1e-3 * T;
  const long samples = out.resampled ? static_cast<long>(std::floor((r.t.back() - t0) / T + 1e-9)) + 1
                                     : static_cast<long>(n);
  for (const ActuatedJoint& a : model.actuated) {
    const std::vector<double>& x = r.at(a.name + ".ref");
    if (!out.resampled) {
      out.ref.push_back(x);
      continue;
    }
    std::vector<double> y(static_cast<std::size_t>(samples));
    for (long k = 0; k < samples; ++k) y[static_cast<std::size_t>(k)] = interpolate(r.t, x, t0 + static_cast<double>(k) * T);
    out.ref.push_back(std::move(y));
  }
  out.lanes.assign(models.begin(), models.end());
  for (ArmModel& m : out.lanes) {
    m.duration = static_cast<double>(samples - 1) * T;
    // The start: the model's, unless the record's first references say otherwise.
    bool moved = false;
    Eigen::VectorXd pose = m.q0;
    for (std::size_t j = 0; j < m.actuated.size(); ++j) {
      const int d = m.actuated[j].dof;
      moved |= std::abs(out.ref[j][0] - pose[d]) > 1e-9;
      pose[d] = out.ref[j][0];
    }
    if (moved) m.q0 = calc_arm_sag(m, pose).q;
  }
  return out;
}

std::map<std::string, std::vector<double>> sample_arm_trace_at_record(const ArmTrace& tr, const ArmModel& m,
                                                                      const Record& r, bool resampled) {
  std::map<std::string, std::vector<double>> out;
  const std::vector<double>& tm = tr.t();
  for (const std::string& c : arm_record_columns(m)) {
    std::vector<double> y = arm_trace_column(tr, m, c, false);
    if (!resampled) {
      out[c] = std::move(y);
      continue;
    }
    std::vector<double> v(r.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = interpolate(tm, y, r.t[k] - r.t.front());
    out[c] = std::move(v);
  }
  return out;
}

std::vector<ArmReplay> replay_arm_records(std::span<const ArmModel> models, const Record& r) {
  const ArmReplaySetup setup = prepare_arm_replay(models, r);
  ArmRunOptions o;
  o.reference = &setup.ref;
  ArmRun run = simulate_arms(setup.lanes, o);
  std::vector<ArmReplay> out(setup.lanes.size());
  for (std::size_t l = 0; l < setup.lanes.size(); ++l) {
    ArmReplay& rp = out[l];
    rp.control_period = setup.lanes[l].control_period;
    rp.resampled = setup.resampled;
    rp.ok = run.status[l] == LaneStatus::kOk;
    rp.trace = std::move(run.traces[l]);
    rp.at_record = sample_arm_trace_at_record(rp.trace, setup.lanes[l], r, setup.resampled);
  }
  return out;
}

ArmReplay replay_arm_record(const ArmModel& model, const Record& r) {
  return std::move(replay_arm_records(std::span<const ArmModel>(&model, 1), r).front());
}

}  // namespace ff
