// The acceptance suite of issue 33 ("An acceptance suite that cannot be tuned to"; docs/validation.md,
// "The acceptance suite of issue 33"). Every record comes from the independent truth simulator
// (tests/validate/truth: absolute segment angles, CVODE, its own regularisations), none from flexfarm's
// own model. With fixed seeds each record hides zero (a third), one or two effects, drawn from forms
// flexfarm does not share (LuGre friction, exponential Stribeck with a shape exponent, a worn gear's
// position-dependent Coulomb level, a multi-slope mesh, backlash whose mesh damps only while the teeth
// close, a logger that records the late value the controller read, a payload change under a controller
// whose feed-forward keeps the nominal payload) and from the truth's other effects. Realistic sensors on
// every record: noise on every channel (in the loop on the angle and the rate), over a decade; a
// quantised encoder in the loop on half the records (its resolution on the model's data sheet); a
// feed-forward controller on some. Moves of many kinds (1-3 moves, amplitudes, move times, holds) and
// record rates (1000, 500, 200 Hz).
//
// The diagnosis starts from the nominal flexfarm model (configs/fbtb.yaml with the record's moves, the
// encoder's resolution and the controller's feed-forward as the rig's data sheet gives them) and runs
// ff::diagnose with its defaults. Each hidden form is right when the diagnosis names one of its accepted
// candidates (kForms below; docs/validation.md lists them). Scored per record: the first-ranked effect
// (Diagnosis::selected's first when diagnose returns a selected set, else ranking[0]), the right set
// (selected, or the verdict split on " + "), the right verdict ("none" when nothing is hidden), false
// `unexplained` and false effects on clean records, and the time per diagnosis. An effect no draw made visible
// is marked "(invisible)" and need not be named (the arm suite's rule).
//
// ctest runs three records (kFastRecords) and asserts each verdict is right, and that the nominal model fits
// the clean one (>= 95 % on every sample channel: the suite's truth-to-model mapping). The whole suite is
//   FLEXFARM_SUITE=full FLEXFARM_SUITE_TABLE=out/diagnosis_acceptance.md \
//       build/tests/test_validate --gtest_filter='DiagnosisAcceptance.*'
// and EXPECTs issue 33's targets (first >= 90 %, verdict >= 85 %, <= 1 in 20 clean records given an
// effect or `unexplained`, every diagnosis within 60 s); FLEXFARM_SUITE_RECORDS=3,7 runs only those
// records and prints each diagnosis; FLEXFARM_SUITE_LIST=1 lists the records without diagnosing them, and
// with FLEXFARM_SUITE_SAVE=DIR writes each as DIR/record_<i>.csv with the model's --set in record_<i>.set
// (for `flexfarm diagnose configs/fbtb.yaml DIR/record_<i>.csv $(cat DIR/record_<i>.set)`).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <type_traits>
#include <utility>

#include "common/random.hpp"
#include "tests/validate/truth/truth_sim.hpp"
#include "validate/diagnose.hpp"
#include "validate/record.hpp"
#include "validate/residuals.hpp"

namespace ff {
namespace {

const std::string kModel = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml";
constexpr std::uint64_t kSuiteSeed = 20261207;
constexpr int kFullRecords = 40;
// ctest: record 36, nothing hidden (one 0.37 rad move, 6 s at 500 Hz); 34, a 12-bit encoder in the loop the
// model does not know; 14, viscous friction and a payload change under the nominal feed-forward (a pair).
const std::vector<int> kFastRecords = {36, 34, 14};

std::string num(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}
double log_uniform(double lo, double hi, double u) { return lo * std::pow(hi / lo, u); }
double uniform(double lo, double hi, double u) { return lo + (hi - lo) * u; }

// What a record's nominal truth looks like before any effect: the numbers the draws scale from.
struct Nominal {
  double peak_torque = 0.0;  // N m, the base record's largest actuator torque
  double rigid_inertia = 0.0;  // kg m^2, the straight arm about the hub
};

// One hidden form: its truth fields drawn at strength u, the flexfarm candidates that name it, and its
// group (a record's two effects come from different groups: not two frictions, not two drives).
using Fields = std::vector<std::pair<std::string, std::string>>;
struct Form {
  std::string name;
  std::string group;
  std::vector<std::string> accepted;
  std::function<Fields(CounterRng&, const Nominal&)> draw;
  bool feedforward = false;  // the record's controller has the nominal feed-forward (the form needs it)
  bool hides_encoder = false;  // the model's data sheet gives no encoder resolution (the form is the encoder)
};

// A drive unlike the model's (which has none): the actuator's share of the hub's 50 kg m^2, mesh
// stiffness (at least `k_min`) and damping (as tests/validate/hidden_effect_suite_test.cpp draws them).
Fields draw_drive(CounterRng& rng, double k_min, double& k) {
  const double ja = 50.0 * log_uniform(0.05, 0.5, rng.uniform());
  k = log_uniform(k_min, 2e8, rng.uniform());
  return {{"drive.enabled", "true"},
          {"drive.inertia", num(ja)},
          {"hub_inertia", num(50.0 - ja)},
          {"drive.stiffness", num(k)},
          {"drive.damping", num(log_uniform(2e3, 3e4, rng.uniform()))}};
}

const std::vector<Form>& forms() {
  static const std::vector<Form> f = {
      // --- forms flexfarm does not share ---
      {"lugre", "friction", {"lugre_friction", "coulomb_friction", "stribeck_friction"},
       [](CounterRng& rng, const Nominal& n) {
         // LuGre (Canudas de Wit 1995): Stribeck curve Fc .. Fs, bristles deflecting z0 = Fc/sigma0 at
         // breakaway, damped at 0.3 of critical on the rigid arm.
         const double fc = log_uniform(60, 600, rng.uniform()), z0 = log_uniform(2e-5, 2e-4, rng.uniform());
         const double sigma0 = fc / z0;
         return Fields{{"friction.coulomb", num(fc)},
                       {"friction.stiction", num(fc * uniform(1.2, 2.5, rng.uniform()))},
                       {"friction.stribeck_velocity", num(log_uniform(0.005, 0.05, rng.uniform()))},
                       {"friction.bristle_stiffness", num(sigma0)},
                       {"friction.bristle_damping", num(0.6 * std::sqrt(sigma0 * n.rigid_inertia))}};
       }},
      {"exponential_stribeck", "friction", {"stribeck_friction", "coulomb_friction"},
       [](CounterRng& rng, const Nominal&) {
         const double fc = log_uniform(100, 400, rng.uniform());
         const double delta[] = {0.5, 1.0, 1.5, 3.0};
         return Fields{{"friction.coulomb", num(fc)},
                       {"friction.stiction", num(fc * uniform(2.0, 4.0, rng.uniform()))},
                       {"friction.stribeck_velocity", num(log_uniform(0.01, 0.05, rng.uniform()))},
                       {"friction.stribeck_exponent", num(delta[rng.next_below(4)])}};
       }},
      {"worn_gear_friction", "friction", {"worn_gear_friction", "coulomb_friction"},
       [](CounterRng& rng, const Nominal&) {
         // Coulomb level Fc (1 + a cos(p theta + phase)): p waves per hub revolution.
         return Fields{{"friction.coulomb", num(log_uniform(100, 600, rng.uniform()))},
                       {"friction.position_amplitude", num(uniform(0.3, 0.8, rng.uniform()))},
                       {"friction.position_waves", num(std::round(uniform(8, 40, rng.uniform())))},
                       {"friction.position_phase", num(uniform(0, 2 * M_PI, rng.uniform()))}};
       }},
      {"multi_slope_mesh", "drive", {"mesh_hardening", "drive_compliance"},
       [](CounterRng& rng, const Nominal& n) {
         double k = 0.0;
         Fields s = draw_drive(rng, 3e5, k);
         // The first knee at a fraction of the move's peak twist, then 2-5 x stiffer; a third slope on half.
         const double knee = uniform(0.2, 0.5, rng.uniform()) * n.peak_torque / k;
         const double k2 = k * uniform(2.0, 5.0, rng.uniform());
         s.insert(s.end(), {{"drive.knee_1", num(knee)}, {"drive.stiffness_2", num(k2)}});
         if (rng.uniform() < 0.5)
           s.insert(s.end(), {{"drive.knee_2", num(knee * uniform(2.0, 3.0, rng.uniform()))},
                              {"drive.stiffness_3", num(k2 * uniform(1.5, 3.0, rng.uniform()))}});
         return s;
       }},
      {"one_sided_backlash", "drive", {"impact_backlash", "backlash"},
       [](CounterRng& rng, const Nominal&) {
         double k = 0.0;
         Fields s = draw_drive(rng, 3e7, k);
         s.insert(s.end(), {{"drive.backlash", num(log_uniform(2e-4, 3e-3, rng.uniform()))},
                            {"drive.one_sided_damping", "true"}});
         return s;
       }},
      {"late_logger_delay", "delay", {"sensor_delay.hub_angle"},
       [](CounterRng& rng, const Nominal&) {
         // The hub angle reaches the controller late and the logger records what the controller read.
         return Fields{{"sensors.hub_angle.delay", num(std::round(log_uniform(2, 12, rng.uniform())))},
                       {"record.as_seen", "true"}};
       }},
      {"payload_nominal_feedforward", "payload", {"payload"},
       [](CounterRng& rng, const Nominal&) {
         // The plant's payload changes; the controller's feed-forward keeps the nominal 328.7 kg, 118.6 kg m^2.
         return Fields{{"payload.mass", num(328.7 * log_uniform(0.6, 1.6, rng.uniform()))},
                       {"payload.inertia", num(118.6 * log_uniform(0.6, 1.6, rng.uniform()))}};
       },
       true},
      // --- the truth's other effects ---
      {"coulomb", "friction", {"coulomb_friction"},
       [](CounterRng& rng, const Nominal&) { return Fields{{"friction.coulomb", num(log_uniform(60, 600, rng.uniform()))}}; }},
      {"viscous", "friction", {"viscous_friction"},
       [](CounterRng& rng, const Nominal&) { return Fields{{"friction.viscous", num(log_uniform(500, 8000, rng.uniform()))}}; }},
      {"stribeck", "friction", {"stribeck_friction", "coulomb_friction"},
       [](CounterRng& rng, const Nominal&) {
         const double fc = log_uniform(100, 400, rng.uniform());
         return Fields{{"friction.coulomb", num(fc)},
                       {"friction.stiction", num(fc * uniform(2.0, 4.0, rng.uniform()))},
                       {"friction.stribeck_velocity", num(log_uniform(0.01, 0.05, rng.uniform()))}};
       }},
      {"backlash", "drive", {"backlash"},
       [](CounterRng& rng, const Nominal&) {
         double k = 0.0;
         Fields s = draw_drive(rng, 3e7, k);
         s.emplace_back("drive.backlash", num(log_uniform(2e-4, 3e-3, rng.uniform())));
         return s;
       }},
      {"drive_compliance", "drive", {"drive_compliance"},
       [](CounterRng& rng, const Nominal&) {
         double k = 0.0;
         return draw_drive(rng, 3e5, k);
       }},
      {"torque_offset", "offset", {"torque_offset"},
       [](CounterRng& rng, const Nominal&) {
         return Fields{{"torque_offset", num((rng.uniform() < 0.5 ? -1 : 1) * log_uniform(60, 800, rng.uniform()))}};
       }},
      {"hub_angle_delay", "delay", {"loop_delay.hub_angle", "sensor_delay.hub_angle"},
       [](CounterRng& rng, const Nominal&) {
         return Fields{{"sensors.hub_angle.delay", num(std::round(log_uniform(2, 12, rng.uniform())))}};
       }},
      {"tip_deflection_delay", "delay", {"sensor_delay.tip_deflection"},
       [](CounterRng& rng, const Nominal&) {
         return Fields{{"sensors.tip_deflection.delay", num(std::round(log_uniform(3, 100, rng.uniform())))}};
       }},
      {"hub_torque_delay", "delay", {"sensor_delay.hub_torque"},
       [](CounterRng& rng, const Nominal&) {
         return Fields{{"sensors.hub_torque.delay", num(std::round(log_uniform(3, 100, rng.uniform())))}};
       }},
      {"quantised_encoder", "encoder", {"sensor_quantization"},
       [](CounterRng& rng, const Nominal&) {
         // An 11-13-bit encoder in the loop the model's data sheet does not mention.
         return Fields{{"sensors.hub_angle.quantize", "true"},
                       {"sensors.hub_angle.encoder_bits", std::to_string(11 + rng.next_below(3))}};
       },
       false, true},
      {"stiffening_joints", "joint", {"joint_stiffening"},
       [](CounterRng& rng, const Nominal&) {
         const double k3 = log_uniform(2e6, 1e8, rng.uniform());  // N m/rad^3 at the reference cell
         return Fields{{"joint.stiffening_angle", "0.01"}, {"joint.stiffening", num(k3 * 1e-4 / 39.5e3)}};
       }},
      {"extra_segments", "segments", {"extra_mode"},
       [](CounterRng& rng, const Nominal&) { return Fields{{"segments", rng.uniform() < 0.5 ? "12" : "16"}}; }},
      {"payload", "payload", {"payload"},
       [](CounterRng& rng, const Nominal&) {
         return Fields{{"payload.mass", num(328.7 * log_uniform(0.6, 1.6, rng.uniform()))},
                       {"payload.inertia", num(118.6 * log_uniform(0.6, 1.6, rng.uniform()))}};
       }},
  };
  return f;
}

const Form& form(const std::string& name) {
  for (const auto& f : forms())
    if (f.name == name) return f;
  throw std::invalid_argument("no form " + name);
}

// The record's rig apart from its hidden effects: moves, rates, sensors, controller.
struct Rig {
  std::vector<truth::TruthMove> moves;
  double move_time = 3.0;
  int decimate = 1;
  double noise = 0.0;          // level in [0, 1]: each channel's noise over its decade
  int encoder_bits = 0;        // in-loop encoder on the data sheet (0 = an ideal angle reading)
  bool feedforward = false;    // the controller's nominal feed-forward, gain 1
  std::uint64_t seed = 0;
};

struct Case {
  int id = 0;
  std::vector<std::string> forms;  // hidden, empty = clean
  Rig rig;
  std::vector<Fields> effects;     // each form's drawn fields
  std::vector<std::string> model_set;  // the nominal flexfarm model's --set
  Record record;
  std::string describe;
  double visibility = INFINITY;    // the least visible effect's RMS change / noise
  std::vector<bool> visible;       // each form's: no draw of kRedraws changed the record by its noise = false
};

// The truth of `c` with `effects`; `noisy` false: every channel's noise off (deterministic, for visibility).
truth::TruthRig make_truth(const Rig& g, const std::vector<Fields>& effects, bool noisy) {
  truth::TruthRig r;
  r.trajectory.moves = g.moves;
  r.trajectory.move_time = g.move_time;
  r.record.decimate = g.decimate;
  r.seed = g.seed;
  if (g.encoder_bits > 0) {
    r.sensors.hub_angle.quantize = true;
    r.sensors.hub_angle.encoder_bits = g.encoder_bits;
  }
  if (g.feedforward) {
    r.controller.feedforward = 1.0;  // nominal hub 50 and payload 328.7 kg, 118.6 kg m^2 (the plant may differ)
    r.controller.nominal_hub_inertia = 50.0;
    r.controller.nominal_payload_mass = 328.7;
    r.controller.nominal_payload_inertia = 118.6;
  }
  if (noisy) {
    // In-loop noise over a decade: encoder 1e-5 .. 1e-4 rad, tachometer 5e-4 .. 5e-3 rad/s (the logger's
    // torque and tip noise: make_case).
    const double f = std::pow(10.0, g.noise);
    r.sensors.hub_angle.noise = 1e-5 * f;
    r.sensors.hub_rate.noise = 5e-4 * f;
  }
  for (const auto& e : effects)
    for (const auto& [k, v] : e) set_truth_field(r, k, v);
  return r;
}

// RMS change of each scored channel over its noise; the largest.
double calc_visibility(const Record& with, const Record& without, const std::map<std::string, double>& noise) {
  double v = 0.0;
  for (const auto& [c, sd] : noise) {
    if (!with.has(c) || !without.has(c)) continue;
    const auto &a = with.at(c), &b = without.at(c);
    const std::size_t n = std::min(a.size(), b.size());
    double s2 = 0.0;
    for (std::size_t k = 0; k < n; ++k) s2 += (a[k] - b[k]) * (a[k] - b[k]);
    v = std::max(v, std::sqrt(s2 / n) / sd);
  }
  return v;
}

// A record a rig could make: finite, the hub within 1.5 x the largest target + 0.1 rad, the torque within
// 10 x the peak without the effect (a rig's limits trip otherwise; such a draw is drawn again).
bool holds_the_arm(const Record& with, double peak0, double reach) {
  for (double x : with.at("hub_angle"))
    if (!std::isfinite(x) || std::fabs(x) > 1.5 * reach + 0.1) return false;
  for (double x : with.at("hub_torque"))
    if (!std::isfinite(x) || std::fabs(x) > 10.0 * peak0) return false;
  return true;
}

constexpr double kMinVisibility = 1.0;
constexpr int kRedraws = 8;

// Record i: i % 3 == 0 clean; i % 3 == 1 one effect, the forms in turn; i % 3 == 2 two effects (every other
// time, else one, continuing the turn).
Case make_case(int i) {
  CounterRng rng(calc_variant_seed(kSuiteSeed, static_cast<std::uint64_t>(i)));
  Case c;
  c.id = i;
  const auto& all = forms();
  int single = 0;  // one-effect records before this one
  for (int j = 0; j < i; ++j) single += j % 3 == 1 || (j % 3 == 2 && (j / 3) % 2 == 1);
  if (i % 3 == 1 || (i % 3 == 2 && (i / 3) % 2 == 1)) {
    c.forms = {all[single % all.size()].name};
  } else if (i % 3 == 2) {
    const Form& a = all[rng.next_below(all.size())];
    std::vector<const Form*> other;
    for (const auto& f : all)
      if (f.group != a.group) other.push_back(&f);
    c.forms = {a.name, other[rng.next_below(other.size())]->name};
  }
  // The move(s), record rate, noise, the sensors and controller of the rig.
  Rig& g = c.rig;
  const int moves = 1 + static_cast<int>(rng.next_below(3));
  g.move_time = moves == 3 ? uniform(1.5, 2.5, rng.uniform()) : uniform(2.0, 4.0, rng.uniform());
  double at = 0.0;
  for (int m = 0; m < moves; ++m) {
    double target = 0.0;
    do target = (rng.uniform() < 0.5 ? -1 : 1) * log_uniform(0.2, 0.8, rng.uniform());
    while (std::fabs(target - at) < 0.15);
    g.moves.push_back({target, moves == 3 ? uniform(1.5, 2.5, rng.uniform()) : uniform(2.0, 4.0, rng.uniform())});
    at = target;
  }
  g.decimate = std::vector<int>{1, 2, 5}[rng.next_below(3)];
  g.noise = rng.uniform();
  g.seed = 5000 + static_cast<std::uint64_t>(i);
  bool hides_encoder = false, feedforward = false;
  for (const auto& f : c.forms) {
    hides_encoder = hides_encoder || form(f).hides_encoder;
    feedforward = feedforward || form(f).feedforward;
  }
  const bool encoder = rng.uniform() < 0.5, ff = rng.uniform() < 0.25;
  g.encoder_bits = hides_encoder || !encoder ? 0 : 15 + static_cast<int>(rng.next_below(3));
  g.feedforward = feedforward || ff;
  double reach = 0.0;
  for (const auto& m : g.moves) reach = std::max(reach, std::fabs(m.target));

  // The nominal record (noise-free): its peak torque and the channels' scales for noise and visibility.
  const Record base = truth::simulate_truth(make_truth(g, {}, false));
  Nominal nominal;
  for (double x : base.at("hub_torque")) nominal.peak_torque = std::max(nominal.peak_torque, std::fabs(x));
  nominal.rigid_inertia = truth::calc_truth_rigid_inertia(truth::TruthRig{});
  const double f = std::pow(10.0, g.noise);
  const double q = g.encoder_bits > 0 ? 2 * M_PI / std::ldexp(1.0, g.encoder_bits) : 0.0;
  const std::map<std::string, double> noise = {
      {"hub_angle", std::hypot(1e-5 * f, q / std::sqrt(12.0))},
      {"hub_torque", 0.003 * f * calc_standard_deviation(base.at("hub_torque"))},
      {"tip_deflection", 0.003 * f * calc_standard_deviation(base.at("tip_deflection"))}};

  // Each hidden effect, drawn again until it is visible and the arm is held.
  for (const auto& name : c.forms) {
    const Form& fm = form(name);
    Fields st;
    double v = 0.0;
    int draws = 0;
    while (draws++ < kRedraws) {
      st = fm.draw(rng, nominal);
      v = 0.0;
      try {
        const Record with = truth::simulate_truth(make_truth(g, {st}, false));
        if (!holds_the_arm(with, nominal.peak_torque, reach)) continue;
        v = calc_visibility(with, base, noise);
      } catch (const std::exception&) {  // a truth that does not run
        continue;
      }
      if (v >= kMinVisibility) break;
    }
    c.visibility = std::min(c.visibility, v);
    c.visible.push_back(v >= kMinVisibility);
    c.effects.push_back(st);
  }

  // The record: every channel noisy (angle and rate in the loop, torque and tip at the logger).
  truth::TruthRig rig = make_truth(g, c.effects, true);
  rig.sensors.hub_torque.noise = noise.at("hub_torque");
  rig.sensors.tip_deflection.noise = noise.at("tip_deflection");
  c.record = truth::simulate_truth(rig);

  // The nominal flexfarm model: the rig's moves, its encoder and feed-forward as its data sheet gives them.
  std::string mv = "trajectory.moves=[";
  for (std::size_t m = 0; m < g.moves.size(); ++m)
    mv += (m ? ", " : "") + std::string("{target: ") + num(g.moves[m].target) + ", hold: " + num(g.moves[m].hold) + "}";
  c.model_set = {mv + "]", "trajectory.move_time=" + num(g.move_time)};
  if (g.encoder_bits > 0) c.model_set.push_back("sensors.hub_angle.resolution=" + num(q));
  if (g.feedforward) c.model_set.push_back("controller.feedforward=1");

  char d[200];
  std::snprintf(d, sizeof d, "%zu move(s) to %.2f rad, T %.1f s, %.0f s, %d Hz, noise %.2f, encoder %d bits%s",
                g.moves.size(), g.moves.back().target, g.move_time, c.record.t.back(), 1000 / g.decimate, g.noise,
                g.encoder_bits, g.feedforward ? ", feed-forward" : "");
  c.describe = d;
  for (const auto& e : c.effects)
    for (const auto& [k, v] : e) c.describe += " " + k + "=" + v;
  if (!c.forms.empty()) c.describe += ", least visible " + num(c.visibility) + " x noise";
  return c;
}

// Diagnosis::selected (the forward selection's set, when diagnose has it), else nothing.
template <class D, class = void>
struct HasSelected : std::false_type {};
template <class D>
struct HasSelected<D, std::void_t<decltype(std::declval<const D&>().selected)>> : std::true_type {};
template <class D>
std::vector<std::string> selected_effects(const D& d) {
  std::vector<std::string> out;
  if constexpr (HasSelected<D>::value)
    for (const auto& e : d.selected) out.push_back(e.effect);
  return out;
}

// "backlash + sensor_quantization" -> {backlash, sensor_quantization}; "none" and "unexplained" -> {}.
std::vector<std::string> split_verdict(const std::string& v) {
  std::vector<std::string> out;
  if (v == "none" || v == "unexplained") return out;
  std::size_t at = 0;
  while (true) {
    const auto plus = v.find(" + ", at);
    out.push_back(v.substr(at, plus == std::string::npos ? std::string::npos : plus - at));
    if (plus == std::string::npos) break;
    at = plus + 3;
  }
  return out;
}

bool accepts(const std::string& form_name, const std::string& effect) {
  const auto& a = form(form_name).accepted;
  return std::find(a.begin(), a.end(), effect) != a.end();
}

// A set of named effects matches the hidden forms: one accepted name per visible form, and any name left
// over one of an invisible form (which no diagnosis need find: as the arm suite scores them).
bool matches(const Case& c, const std::vector<std::string>& named) {
  std::vector<std::string> rest = named;
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t k = 0; k < c.forms.size(); ++k) {
      if (c.visible[k] != (pass == 0)) continue;
      const auto it = std::find_if(rest.begin(), rest.end(), [&](const std::string& e) { return accepts(c.forms[k], e); });
      if (it != rest.end()) rest.erase(it);
      else if (c.visible[k]) return false;
    }
  return rest.empty();
}

// The record's hidden forms as the tables name them, an invisible one marked.
std::string hidden_names(const Case& c) {
  if (c.forms.empty()) return "—";
  std::string s;
  for (std::size_t k = 0; k < c.forms.size(); ++k)
    s += (k ? " + " : "") + std::string(c.visible[k] ? "" : "(invisible) ") + c.forms[k];
  return s;
}

struct Outcome {
  std::string first, verdict;
  int rank = 0;  // of the first hidden form's accepted effect in the ranking (0: not ranked)
  double base_fit = NAN;  // the nominal model's worst sample channel, fit %
  std::vector<std::string> set;
  bool scored_first = false;  // a visible form is hidden: the first-ranked effect is scored
  bool first_ok = false, set_ok = false, verdict_ok = false;
  bool false_unexplained = false, false_effect = false;  // clean records
  double seconds = NAN;
};

Outcome run_case(const Case& c, bool print) {
  const ModelSource model = load_model_source(kModel, c.model_set);
  const auto t0 = std::chrono::steady_clock::now();
  const Diagnosis d = diagnose(model, c.record, DiagnoseOptions{});
  Outcome o;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto selected = selected_effects(d);
  o.first = !selected.empty() ? selected[0] : d.ranking.empty() ? "" : d.ranking[0].effect;
  o.verdict = d.verdict;
  o.set = HasSelected<Diagnosis>::value ? selected : split_verdict(d.verdict);
  const auto named = split_verdict(d.verdict);
  o.base_fit = INFINITY;
  for (const auto& [ch, fit] : d.base_fit)
    if (ch.find('.') == std::string::npos) o.base_fit = std::min(o.base_fit, fit);
  for (std::size_t j = 0; j < d.ranking.size() && o.rank == 0; ++j)
    for (const auto& f : c.forms)
      if (accepts(f, d.ranking[j].effect)) o.rank = static_cast<int>(j) + 1;
  if (c.forms.empty()) {
    o.first_ok = o.verdict_ok = d.verdict == "none";
    o.set_ok = o.set.empty();
    o.false_unexplained = d.verdict == "unexplained";
    o.false_effect = !named.empty();
  } else {
    for (std::size_t k = 0; k < c.forms.size(); ++k) {
      o.scored_first = o.scored_first || c.visible[k];
      o.first_ok = o.first_ok || (c.visible[k] && accepts(c.forms[k], o.first));
    }
    o.set_ok = matches(c, o.set);
    o.verdict_ok = d.verdict != "unexplained" && matches(c, named);
  }
  if (print)
    std::printf("record %d [%s]: %s\n%s\n", c.id, c.forms.empty() ? "clean" : hidden_names(c).c_str(), c.describe.c_str(),
                format_diagnosis_text(d).c_str());
  return o;
}

std::string percent(int a, int n) {
  char b[32];
  std::snprintf(b, sizeof b, "%d / %d (%.0f %%)", a, n, n ? 100.0 * a / n : 0.0);
  return b;
}

TEST(DiagnosisAcceptance, TruthRecordsWithEffectsInForeignFormsAreDiagnosed) {
  const bool full = std::getenv("FLEXFARM_SUITE") && std::string(std::getenv("FLEXFARM_SUITE")) == "full";
  std::vector<int> ids;
  if (full)
    for (int i = 0; i < kFullRecords; ++i) ids.push_back(i);
  else
    ids = kFastRecords;
  const char* only = std::getenv("FLEXFARM_SUITE_RECORDS");
  if (only) {
    ids.clear();
    for (const char* p = only; *p;) {
      char* end = nullptr;
      ids.push_back(static_cast<int>(std::strtol(p, &end, 10)));
      p = *end ? end + 1 : end;
    }
  }
  const int n = static_cast<int>(ids.size());
  if (std::getenv("FLEXFARM_SUITE_LIST")) {  // the records alone, no diagnosis
    const char* dir = std::getenv("FLEXFARM_SUITE_SAVE");  // and each record's CSV and the model's --set there
    for (int id : ids) {
      const Case c = make_case(id);
      std::printf("record %d [%s]: %s\n", id, c.forms.empty() ? "clean" : hidden_names(c).c_str(), c.describe.c_str());
      if (!dir) continue;
      const std::string stem = std::string(dir) + "/record_" + std::to_string(id);
      std::vector<std::string> columns;
      for (const char* k : {"ref", "hub_torque", "hub_angle", "hub_rate", "tip_deflection", "pressure_a", "pressure_b"})
        if (c.record.has(k)) columns.push_back(k);
      write_record_csv(c.record, columns, stem + ".csv", 17);
      std::ofstream args(stem + ".set");
      for (const auto& s : c.model_set) args << "--set '" << s << "' ";
    }
    return;
  }
  std::vector<Case> cases(n);
  std::vector<Outcome> out(n);
  // One record at a time: diagnose uses both cores itself, and the times are per diagnosis.
  for (int i = 0; i < n; ++i) {
    cases[i] = make_case(ids[i]);
    out[i] = run_case(cases[i], only != nullptr);
  }

  // Per form (a pair counts under each of its forms) and in total.
  struct Tally {
    int records = 0, scored_first = 0, first = 0, set = 0, verdict = 0;
    double seconds = 0.0;
  };
  std::map<std::string, Tally> by;
  Tally all, clean, hidden;
  int false_unexplained = 0, false_effect = 0;
  double worst_seconds = 0.0;
  std::string rows;
  for (int i = 0; i < n; ++i) {
    const Case& c = cases[i];
    const Outcome& o = out[i];
    std::vector<Tally*> tallies = {&all, c.forms.empty() ? &clean : &hidden};
    if (c.forms.empty()) tallies.push_back(&by["(clean)"]);
    for (std::size_t k = 0; k < c.forms.size(); ++k)
      tallies.push_back(&by[(c.visible[k] ? "" : "(invisible) ") + c.forms[k] + (c.forms.size() > 1 ? " (in a pair)" : "")]);
    for (Tally* t : tallies) {
      t->records++;
      t->scored_first += o.scored_first;
      t->first += o.first_ok;
      t->set += o.set_ok;
      t->verdict += o.verdict_ok;
      t->seconds += o.seconds;
    }
    false_unexplained += o.false_unexplained;
    false_effect += o.false_effect;
    worst_seconds = std::max(worst_seconds, o.seconds);
    std::string set;
    for (const auto& e : o.set) set += (set.empty() ? "" : " + ") + e;
    char line[1400];
    std::snprintf(line, sizeof line, "| %d | %s | %s | %s%s | %s | %s | %.0f |\n", c.id, hidden_names(c).c_str(), c.describe.c_str(),
                  o.first.c_str(), o.first_ok ? " ✓" : "", set.empty() ? "—" : set.c_str(), o.verdict.c_str(), o.seconds);
    rows += line;
  }
  std::string table = "| hidden form | records | first | right set | right verdict | mean time (s) |\n|---|---|---|---|---|---|\n";
  auto row = [&](const std::string& k, const Tally& t) {
    char line[400];
    std::snprintf(line, sizeof line, "| %s | %d | %d | %d | %d | %.0f |\n", k.c_str(), t.records, t.first, t.set, t.verdict,
                  t.records ? t.seconds / t.records : 0.0);
    table += line;
  };
  for (const auto& [k, t] : by) row("`" + k + "`", t);
  row("**with an effect**", hidden);
  row("**clean**", clean);
  row("**all**", all);
  table += "\nFirst-ranked right (records with a visible effect): " + percent(hidden.first, hidden.scored_first) +
           " (target >= 90 %); right verdict (all records): " + percent(all.verdict, all.records) +
           " (target >= 85 %); clean records given an effect or `unexplained`: " +
           percent(false_effect + false_unexplained, clean.records) + " (target <= 5 %; `unexplained` " +
           std::to_string(false_unexplained) + ", an effect " + std::to_string(false_effect) + "); longest diagnosis " +
           num(std::round(worst_seconds)) + " s (target <= 60 s).\n";
  const std::string detail = "\n| record | hidden | truth | first | set | verdict | s |\n|---|---|---|---|---|---|---|\n" + rows;
  std::printf("%s%s", table.c_str(), detail.c_str());
  if (full || only) {
    const char* path = std::getenv("FLEXFARM_SUITE_TABLE");
    if (path) std::ofstream(path) << table << detail;
  }
  if (only) return;
  if (full) {  // issue 33, "Done when"
    EXPECT_GE(hidden.first, 0.90 * hidden.scored_first) << table;
    EXPECT_GE(all.verdict, 0.85 * all.records) << table;
    EXPECT_LE(false_effect + false_unexplained, 0.05 * clean.records) << table;
    EXPECT_LE(worst_seconds, 60.0) << table;
  } else {
    // The nominal model replays the clean truth record closely on every sample channel (the suite's mapping
    // of truth to model is right); every verdict is right: `none`, `sensor_quantization`, the pair.
    ASSERT_EQ(n, 3);
    ASSERT_TRUE(cases[0].forms.empty());
    EXPECT_GE(out[0].base_fit, 95.0) << detail;
    for (int i = 0; i < n; ++i) EXPECT_TRUE(out[i].verdict_ok) << "record " << cases[i].id << "\n" << detail;
  }
}

}  // namespace
}  // namespace ff
