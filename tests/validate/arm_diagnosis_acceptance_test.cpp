// The arm diagnosis acceptance suite of issue 33 (docs/validation.md, "Arm acceptance on the truth
// arm"): records drawn, with fixed seeds, from the independent truth arm (tests/validate/truth_arm/), not
// from flexfarm's own arm model: the 2-, 3- and 6-joint suite arms, each record with zero, one or two
// hidden effects at random joints in forms flexfarm does not share (LuGre, exponential-Stribeck and
// position-dependent friction, a multi-slope mesh, one-sided damped backlash, a torque offset, a heavier
// or lighter payload the controller does not know, an angle logged late, an encoder quantised in the
// loop), random moves, noise on every channel at random levels. The nominal flexfarm models are
// tests/data/truth_arm/arm<n>.yaml; diagnose_arm runs with its defaults on each record. Scores:
//   first     the ranking's first is one of the hidden effects (records with a visible effect)
//   set       the first k of the ranking are the k visible hidden effects
//   verdict   the verdict, split on " + ", is the hidden set ("none" on a clean record; an invisible
//             effect may be named or not)
//   clean     a clean record given an effect or "unexplained"
// An effect is drawn again (up to 8 times) until it is visible (is_visible: it changes the noise-free
// record by the noise on some channel, in a run a rig could make); one no draw made visible is marked
// "(invisible)" in the table and need not be found.
// ctest runs two short records over a few candidates with robust assertions only; the whole suite, with issue 33's
// targets (>= 90 % first, >= 85 % right verdict, <= 1 in 20 clean records given an effect or
// unexplained), is
//   FLEXFARM_SUITE=full build/tests/test_validate --gtest_filter='ArmDiagnosisAcceptance.*'
// FLEXFARM_SUITE_RECORDS=3,7 runs only those (printing each diagnosis); FLEXFARM_SUITE_LIST=1 prints the
// draws and diagnoses nothing; FLEXFARM_SUITE_TABLE=FILE.md writes the per-record table and the scores
// as markdown.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "sweep/paths.hpp"
#include "tests/validate/truth_arm/truth_arm.hpp"
#include "validate/arm_diagnose.hpp"
#include "validate/arm_record.hpp"
#include "validate/residuals.hpp"

namespace ff {
namespace {

using truth::TruthArm;

constexpr std::uint64_t kSuiteSeed = 20261207;
constexpr int kFullRecords = 40;

// One hidden effect as drawn: what was set in the truth, and the candidate names that count as finding it.
struct Hidden {
  std::string kind;                     // the truth's form, e.g. "lugre@j2"
  std::vector<std::string> fields;      // KEY=VALUE on the truth arm
  std::set<std::string> accepted;       // arm_diagnose candidate names (validate/arm_diagnose.cpp)
  bool visible = true;                  // is_visible: no draw of 8 was, then it need not be found
};

struct Case {
  int joints = 2;
  TruthArm arm;                         // with the hidden effects, the noise and the move applied
  std::vector<Hidden> hidden;
  std::vector<std::string> nominal_set; // the nominal model's --set: the record's duration
};

double log_uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo * std::pow(hi / lo, std::uniform_real_distribution<double>(0.0, 1.0)(rng));
}
double uniform(std::mt19937_64& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
std::string num(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

const char* const kKinds[] = {"lugre", "stribeck", "position_friction", "multislope_mesh", "backlash",
                              "torque_offset", "payload", "late_angle", "encoder"};

// Draws hidden effect `kind` at joint j (0-based), scaled by that joint's torque and rate RMS on the clean record.
Hidden draw_effect(std::mt19937_64& rng, const std::string& kind, int j, const TruthArm& a, double tau, double w) {
  const std::string J = truth::truth_arm_joint_name(j), p = J + ".";
  const auto& c = a.joint[static_cast<std::size_t>(j)].controller;
  Hidden h;
  h.kind = kind + "@" + J;
  if (kind == "lugre" || kind == "stribeck" || kind == "position_friction") {
    const double fc = tau * log_uniform(rng, 0.05, 0.4);
    h.fields = {p + "friction.coulomb=" + num(fc)};
    h.accepted = {"coulomb_friction@" + J, "stribeck_friction@" + J};
    if (kind == "lugre") {
      h.accepted.insert("lugre_friction@" + J);
      h.fields.push_back(p + "friction.lugre=true");
      h.fields.push_back(p + "friction.stiction=" + num(fc * uniform(rng, 1.0, 1.8)));
      h.fields.push_back(p + "friction.stribeck_velocity=" + num(w * log_uniform(rng, 0.01, 0.1)));
      h.fields.push_back(p + "friction.bristle_stiffness=" + num(fc * log_uniform(rng, 300.0, 3000.0)));  // 0.3-3 mrad pre-slip
      h.fields.push_back(p + "friction.bristle_damping=" + num(fc * log_uniform(rng, 1.0, 10.0)));
    } else if (kind == "stribeck") {
      h.fields.push_back(p + "friction.stiction=" + num(fc * uniform(rng, 1.3, 2.5)));
      h.fields.push_back(p + "friction.stribeck_velocity=" + num(w * log_uniform(rng, 0.02, 0.2)));
      h.fields.push_back(p + "friction.stribeck_exponent=" + num(uniform(rng, 0.5, 1.5)));
    } else {
      h.accepted.insert("worn_gear_friction@" + J);
      h.fields.push_back(p + "friction.position_amplitude=" + num(uniform(rng, 0.3, 0.8)));
      h.fields.push_back(p + "friction.position_period=" + num(uniform(rng, 0.2, 1.0)));
      h.fields.push_back(p + "friction.position_phase=" + num(uniform(rng, 0.0, 2.0 * M_PI)));
    }
  } else if (kind == "multislope_mesh" || kind == "backlash") {
    const double k = c.kp * log_uniform(rng, 3.0, 60.0);
    h.fields = {p + "drive.compliant=true", p + "drive.stiffness=" + num(k),
                p + "drive.damping=" + num(k * log_uniform(rng, 2e-4, 2e-3))};
    if (kind == "multislope_mesh") {
      h.fields.push_back(p + "drive.knee=" + num(log_uniform(rng, 2e-4, 2e-3)));
      h.fields.push_back(p + "drive.stiffness2=" + num(k * uniform(rng, 2.0, 6.0)));
      h.accepted = {"mesh_hardening@" + J, "drive_compliance@" + J, "backlash@" + J};
    } else {
      h.fields.push_back(p + "drive.backlash=" + num(log_uniform(rng, 1e-3, 8e-3)));
      h.accepted = {"backlash@" + J};
    }
  } else if (kind == "torque_offset") {
    const double sign = uniform(rng, 0.0, 1.0) < 0.5 ? -1.0 : 1.0;
    h.fields = {p + "torque_offset=" + num(sign * tau * log_uniform(rng, 0.05, 0.5))};
    h.accepted = {"torque_offset@" + J};
  } else if (kind == "payload") {
    h.kind = "payload";
    const double f = std::exp((uniform(rng, 0.0, 1.0) < 0.5 ? -1.0 : 1.0) * uniform(rng, std::log(1.3), std::log(3.0)));
    h.fields = {"controller.payload_mass=" + num(a.payload.mass), "payload.mass=" + num(a.payload.mass * f)};
    h.accepted = {"payload@payload"};
  } else if (kind == "late_angle") {
    const int most = std::max(3, static_cast<int>(0.04 * a.controller.rate));
    h.fields = {p + "sensors.angle.delay=" + std::to_string(std::uniform_int_distribution<int>(2, most)(rng))};
    h.accepted = {"sensor_delay." + J + "_angle"};
  } else {  // encoder
    h.fields = {p + "sensors.angle.encoder_bits=" + std::to_string(std::uniform_int_distribution<int>(12, 15)(rng))};
    h.accepted = {"sensor_quantization@" + J};
  }
  return h;
}

void apply_fields(TruthArm& a, const std::vector<std::string>& fields) {
  for (const auto& f : fields) {
    const auto eq = f.find('=');
    truth::set_truth_arm_field(a, f.substr(0, eq), f.substr(eq + 1));
  }
}

// Whether an effect can be found at all: alone on the noise-free arm it changes some joint's angle or
// torque column by at least that channel's noise (RMS), and the run is one a rig could make (it does not
// fail, every torque within ten times the clean run's peak). The criteria know nothing of diagnose.
bool is_visible(const TruthArm& noise_free, const Record& clean, const std::vector<std::string>& fields, double sigma_angle,
                const std::vector<double>& sigma_torque) {
  TruthArm t = noise_free;
  apply_fields(t, fields);
  Record r;
  try {
    r = truth::run_truth_arm(t).record;
  } catch (const std::runtime_error&) {
    return false;
  }
  bool seen = false;
  for (int j = 0; j < noise_free.joints; ++j) {
    const std::string J = truth::truth_arm_joint_name(j);
    const std::vector<double>&qa = r.at(J + ".angle"), &qc = clean.at(J + ".angle"), &ta = r.at(J + ".torque"),
                               &tc = clean.at(J + ".torque");
    double da = 0.0, dt = 0.0, peak = 0.0, peak_clean = 0.0;
    for (std::size_t k = 0; k < qa.size(); ++k) {
      if (!std::isfinite(qa[k]) || !std::isfinite(ta[k])) return false;
      da += (qa[k] - qc[k]) * (qa[k] - qc[k]);
      dt += (ta[k] - tc[k]) * (ta[k] - tc[k]);
      peak = std::max(peak, std::abs(ta[k]));
      peak_clean = std::max(peak_clean, std::abs(tc[k]));
    }
    if (peak > 10.0 * peak_clean) return false;
    const double n = static_cast<double>(qa.size());
    seen |= std::sqrt(da / n) >= sigma_angle || std::sqrt(dt / n) >= sigma_torque[static_cast<std::size_t>(j)];
  }
  return seen;
}

// Record i: the arm (2, 3, 6 joints in turn, 6 less often), the move, the noise, 0-2 effects.
Case draw_case(int i, bool fast) {
  std::mt19937_64 rng(kSuiteSeed + static_cast<std::uint64_t>(i) * 7919u);
  Case c;
  const int arms[] = {2, 3, 2, 6, 3};
  c.joints = fast ? 2 : arms[i % 5];
  TruthArm& a = c.arm;
  a = truth::make_suite_arm(c.joints);
  // The move: 1-2 waypoints, each joint 0.15-0.8 rad from where it was, 0.8-1.5 s each, settle 0.5-1 s.
  a.trajectory.waypoints.clear();
  const int wps = fast ? 1 : std::uniform_int_distribution<int>(1, 2)(rng);
  std::vector<double> at = a.trajectory.start;
  for (int k = 0; k < wps; ++k) {
    TruthArm::Trajectory::Waypoint w;
    w.time = uniform(rng, 0.8, 1.5);
    for (int j = 0; j < c.joints; ++j) {
      const double step = uniform(rng, 0.15, 0.8) * (uniform(rng, 0.0, 1.0) < 0.5 ? -1.0 : 1.0);
      at[static_cast<std::size_t>(j)] = std::clamp(at[static_cast<std::size_t>(j)] + step, -1.2, 1.2);
      w.q.push_back(at[static_cast<std::size_t>(j)]);
    }
    a.trajectory.waypoints.push_back(w);
  }
  a.trajectory.settle = uniform(rng, 0.5, 1.0);
  double duration = a.trajectory.settle;
  for (const auto& w : a.trajectory.waypoints) duration += w.time;
  a.duration = std::round(duration * a.controller.rate) / a.controller.rate;
  c.nominal_set = {"simulation.duration=" + num(a.duration)};  // the replay follows the record's references
  // Each joint's torque and rate RMS on the clean, noise-free record: what strengths and noise scale with.
  const truth::TruthArmRun clean = truth::run_truth_arm(a);
  std::vector<double> tau(static_cast<std::size_t>(c.joints)), w(tau.size());
  for (int j = 0; j < c.joints; ++j) {
    const std::string J = truth::truth_arm_joint_name(j);
    tau[static_cast<std::size_t>(j)] = std::max(calc_rms(clean.record.at(J + ".torque")), 1e-3);
    w[static_cast<std::size_t>(j)] = std::max(calc_rms(clean.record.at(J + ".rate")), 1e-3);
  }
  // Realistic sensors on every record: angle 2e-5-3e-4 rad, rate 10-30x that per rad, torque 0.3-3 % of its RMS.
  const double sa = log_uniform(rng, 2e-5, 3e-4), sr = sa * uniform(rng, 10.0, 30.0), st = log_uniform(rng, 0.003, 0.03);
  const TruthArm noise_free = a;
  std::vector<double> sigma_torque;
  for (double x : tau) sigma_torque.push_back(st * x);
  for (int j = 0; j < c.joints; ++j) {
    auto& s = a.joint[static_cast<std::size_t>(j)].sensors;
    s.angle.noise = sa;
    s.rate.noise = sr;
    s.torque_noise = st * tau[static_cast<std::size_t>(j)];
  }
  a.seed = kSuiteSeed + static_cast<std::uint64_t>(i);
  // 0, 1 or 2 hidden effects (a quarter clean, half one, a quarter two), at distinct joints; each drawn
  // again (up to 8 times) until it is visible.
  const double u = uniform(rng, 0.0, 1.0);
  const int count = fast ? (i % 2) : (u < 0.25 ? 0 : u < 0.75 ? 1 : 2);
  std::vector<int> joints(static_cast<std::size_t>(c.joints));
  for (int j = 0; j < c.joints; ++j) joints[static_cast<std::size_t>(j)] = j;
  std::shuffle(joints.begin(), joints.end(), rng);
  bool payload = false;
  for (int e = 0; e < count; ++e) {
    std::string kind = kKinds[std::uniform_int_distribution<std::size_t>(0, std::size(kKinds) - 1)(rng)];
    if (kind == "payload" && payload) kind = "torque_offset";
    payload |= kind == "payload";
    if (fast) kind = "torque_offset";
    const int j = joints[static_cast<std::size_t>(e)];
    Hidden h;
    for (int attempt = 0; attempt < 8; ++attempt) {
      h = draw_effect(rng, kind, j, a, tau[static_cast<std::size_t>(j)], w[static_cast<std::size_t>(j)]);
      if ((h.visible = is_visible(noise_free, clean.record, h.fields, sa, sigma_torque))) break;
    }
    // Free play that the load keeps closed (a joint whose gravity torque never changes sign) shows only
    // as its drive's compliance: when the play itself changes nothing the drive without it would not,
    // drive_compliance@J is right too.
    if (h.visible && kind == "backlash") {
      std::vector<std::string> drive = h.fields;
      const std::string play = drive.back();  // ...drive.backlash=VALUE, drawn last
      drive.pop_back();
      TruthArm without = noise_free;
      apply_fields(without, drive);
      if (!is_visible(without, truth::run_truth_arm(without).record, {play}, sa, sigma_torque)) {
        h.accepted.insert("drive_compliance@" + truth::truth_arm_joint_name(j));
        h.kind += " (play closed by the load)";
      }
    }
    apply_fields(a, h.fields);
    c.hidden.push_back(h);
  }
  return c;
}

// The verdict's effects ("a + b"; "none" and "unexplained" are no effects).
std::vector<std::string> verdict_effects(const std::string& v) {
  std::vector<std::string> out;
  if (v == "none" || v == "unexplained") return out;
  std::size_t from = 0;
  for (std::size_t at; (at = v.find(" + ", from)) != std::string::npos; from = at + 3) out.push_back(v.substr(from, at - from));
  out.push_back(v.substr(from));
  return out;
}

// Whether `names` are the hidden effects: each visible one matched by one name, and any name left over
// matching an invisible one (which may or may not be found).
bool is_hidden_set(const std::vector<std::string>& names, const std::vector<Hidden>& hidden) {
  std::vector<bool> used(names.size(), false);
  for (const Hidden& h : hidden) {
    bool found = false;
    for (std::size_t k = 0; k < names.size() && !found; ++k)
      if (!used[k] && h.accepted.count(names[k])) used[k] = found = true;
    if (!found && h.visible) return false;
  }
  return std::find(used.begin(), used.end(), false) == used.end();
}

int count_visible(const Case& c) {
  return static_cast<int>(std::count_if(c.hidden.begin(), c.hidden.end(), [](const Hidden& h) { return h.visible; }));
}

struct Outcome {
  std::string verdict, first;
  bool first_right = false, set_right = false, verdict_right = false;
  double seconds = 0.0;
};

// `only`: the candidates tried (empty: every candidate, diagnose's default).
Outcome run_case(const Case& c, bool print, const std::vector<std::string>& only = {}) {
  const std::string model = std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/truth_arm/arm" + std::to_string(c.joints) + ".yaml";
  Record r = truth::run_truth_arm(c.arm).record;
  r.source = "<truth arm record>";
  const ModelSource src = load_arm_source(model, c.nominal_set);
  const auto t0 = std::chrono::steady_clock::now();
  DiagnoseOptions opt;
  opt.only = only;
  const Diagnosis d = diagnose_arm(src, r, opt);
  Outcome o;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  o.verdict = d.verdict;
  o.first = d.ranking.empty() ? "-" : d.ranking.front().effect;
  for (const Hidden& h : c.hidden)
    o.first_right |= h.visible && !d.ranking.empty() && h.accepted.count(d.ranking.front().effect) > 0;
  std::vector<std::string> top;
  for (std::size_t k = 0; k < std::min(static_cast<std::size_t>(count_visible(c)), d.ranking.size()); ++k)
    top.push_back(d.ranking[k].effect);
  o.set_right = count_visible(c) > 0 && is_hidden_set(top, c.hidden);
  o.verdict_right = d.verdict != "unexplained" && is_hidden_set(verdict_effects(d.verdict), c.hidden);
  if (print) std::printf("%s", format_diagnosis_text(d).c_str());
  return o;
}

std::string hidden_text(const Case& c) {
  if (c.hidden.empty()) return "none";
  std::string s;
  for (const Hidden& h : c.hidden) s += (s.empty() ? "" : " + ") + (h.visible ? "" : std::string("(invisible) ")) + h.kind;
  return s;
}

// The nominal model replays a clean, noise-free record of each suite arm: the mapping of
// tests/data/truth_arm/README.md holds on the suite's own moves (else every verdict would be wrong).
TEST(ArmDiagnosisAcceptance, NominalModelsExplainCleanTruthRecords) {
  for (int joints : {2, 3, 6}) {
    TruthArm a = truth::make_suite_arm(joints);
    a.duration = 1.2;
    const Record r = truth::run_truth_arm(a).record;
    const ArmModel m = load_arm_with(std::string(FLEXFARM_SOURCE_DIR) + "/tests/data/truth_arm/arm" + std::to_string(joints) + ".yaml",
                                     {"simulation.duration=1.2"});
    check_arm_record(r, m);
    const std::map<std::string, Fit> fits = calc_arm_record_fits(m, r);
    EXPECT_EQ(fits.size(), 2u * static_cast<std::size_t>(joints));  // every angle and torque scored
    for (const auto& [column, fit] : fits) EXPECT_GT(fit.percent, 99.99) << joints << " joints, " << column;
  }
}

// ctest's share (about 30 s): two short two-joint records, one clean and one with a torque offset,
// diagnosed over five candidates only (the full diagnosis of one record takes 35 s of CPU): the offset is
// the verdict, the clean record's verdict is none.
TEST(ArmDiagnosisAcceptance, ATorqueOffsetIsFoundAndACleanRecordIsClean) {
  for (int i : {0, 1}) {
    const Case c = draw_case(i, true);
    const std::string j = c.hidden.empty() ? "j1" : c.hidden.front().kind.substr(c.hidden.front().kind.find('@') + 1);
    const Outcome o = run_case(c, false, {"torque_offset@" + j, "coulomb_friction@" + j, "viscous_friction@" + j,
                                          "sensor_delay." + j + "_angle", "payload@payload"});
    EXPECT_TRUE(o.verdict_right) << "record " << i << ": hidden " << hidden_text(c) << ", verdict " << o.verdict;
    if (!c.hidden.empty()) EXPECT_TRUE(o.first_right) << "record " << i << ": first " << o.first;
  }
}

TEST(ArmDiagnosisAcceptance, HiddenEffectsAreFoundOnTruthArmRecords) {
  const char* mode = std::getenv("FLEXFARM_SUITE");
  const bool full = mode && std::string(mode) == "full";
  if (!full && !std::getenv("FLEXFARM_SUITE_RECORDS")) GTEST_SKIP() << "the whole suite: FLEXFARM_SUITE=full (about two hours)";
  const bool list = std::getenv("FLEXFARM_SUITE_LIST") != nullptr;  // print the draws, diagnose nothing
  std::vector<int> records;
  if (const char* only = std::getenv("FLEXFARM_SUITE_RECORDS")) {
    std::stringstream in(only);
    for (std::string x; std::getline(in, x, ',');) records.push_back(std::stoi(x));
  } else {
    for (int i = 0; i < kFullRecords; ++i) records.push_back(i);
  }
  const bool print = std::getenv("FLEXFARM_SUITE_RECORDS") != nullptr;
  int effects = 0, first = 0, set = 0, verdicts = 0, cleans = 0, clean_effect = 0, clean_unexplained = 0;
  double seconds = 0.0, slowest = 0.0;
  std::ostringstream table;
  table << "| record | arm | hidden | first ranked | verdict | first | set | verdict right | s |\n"
        << "|---:|---:|---|---|---|:-:|:-:|:-:|---:|\n";
  for (int i : records) {
    const Case c = draw_case(i, false);
    std::string fields;
    for (const Hidden& h : c.hidden)
      for (const auto& f : h.fields) fields += f + " ";
    if (list) {
      std::printf("record %2d  %d joints  %.2f s  hidden %-40s %s\n", i, c.joints, c.arm.duration, hidden_text(c).c_str(), fields.c_str());
      continue;
    }
    const Outcome o = run_case(c, print);
    std::printf("record %2d  %d joints  hidden %-40s first %-28s verdict %-40s %.0f s\n", i, c.joints, hidden_text(c).c_str(),
                o.first.c_str(), o.verdict.c_str(), o.seconds);
    std::printf("           %s\n", fields.c_str());
    seconds += o.seconds;
    slowest = std::max(slowest, o.seconds);
    verdicts += o.verdict_right;
    if (c.hidden.empty()) {
      ++cleans;
      clean_unexplained += o.verdict == "unexplained";
      clean_effect += !verdict_effects(o.verdict).empty();
    } else if (count_visible(c) > 0) {
      ++effects;
      first += o.first_right;
      set += o.set_right;
    }
    char row[512];
    const bool scored = count_visible(c) > 0;
    std::snprintf(row, sizeof row, "| %d | %d | %s | %s | %s | %s | %s | %s | %.0f |\n", i, c.joints, hidden_text(c).c_str(),
                  o.first.c_str(), o.verdict.c_str(), scored ? (o.first_right ? "yes" : "no") : "",
                  scored ? (o.set_right ? "yes" : "no") : "", o.verdict_right ? "yes" : "no", o.seconds);
    table << row;
    // Robust in every mode: a clean record is never given two effects, a diagnosis never fails outright.
    EXPECT_LE(verdict_effects(o.verdict).size(), c.hidden.size() + 1) << "record " << i;
  }
  if (list) return;
  const int n = static_cast<int>(records.size());
  char summary[600];
  std::snprintf(summary, sizeof summary,
                "\n%d records (%d with effects, %d clean): first ranked %d of %d, right set %d of %d, right verdict %d of %d; "
                "clean records given an effect %d, unexplained %d; %.0f s per diagnosis (slowest %.0f s)\n",
                n, effects, cleans, first, effects, set, effects, verdicts, n, clean_effect, clean_unexplained,
                n ? seconds / n : 0.0, slowest);
  std::printf("%s", summary);
  if (const char* file = std::getenv("FLEXFARM_SUITE_TABLE")) {
    std::ofstream out(file);
    out << table.str() << summary;
  }
  if (full && !std::getenv("FLEXFARM_SUITE_RECORDS")) {
    // Issue 33's targets.
    EXPECT_GE(first, static_cast<int>(std::ceil(0.90 * effects)));
    EXPECT_GE(verdicts, static_cast<int>(std::ceil(0.85 * n)));
    EXPECT_LE(20 * (clean_effect + clean_unexplained), cleans);
  }
}

}  // namespace
}  // namespace ff
