// The hub drive (kernel/drive.cpp): hydraulic rotary actuator, drive train with backlash, LuGre
// friction. Each checked against an analytic limit or an invariant.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "kernel/cvode.hpp"
#include "kernel/drive.hpp"
#include "kernel/dynamics.hpp"
#include "common/errors.hpp"
#include "common/random.hpp"
#include "kernel/fixed_step.hpp"
#include "kernel/model_io.hpp"
#include "tests/kernel/test_support.hpp"

namespace ff {
namespace {

BatchModel one_lane(const Model& m) { return make_batch(std::span<const Model>(&m, 1)); }

// The reference rig with a stiff beam (joint springs x100): the arm turns as one body.
ModelSpec stiff_arm() {
  ModelSpec s = test::rig_spec();
  s.joints.stiffness *= 100.0;
  return s;
}

// RMS of the difference of two equally sampled signals.
double rms_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) sum += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(sum / a.size());
}

TEST(Hydraulics, OrificeFlowIsOddLinearThroughZeroAndTurbulentFarFromIt) {
  const double lam = 1e5;
  for (double dp : {1e3, 1e5, 3e6})
    EXPECT_DOUBLE_EQ(calc_orifice_root(-dp, lam), -calc_orifice_root(dp, lam));
  EXPECT_EQ(calc_orifice_root(0.0, lam), 0.0);
  // Laminar core: slope 1 / sqrt(dp_lam) at zero; turbulent: sqrt(dp) far from it.
  EXPECT_NEAR(calc_orifice_root(1.0, lam), 1.0 / std::sqrt(lam), 1e-9);
  EXPECT_NEAR(calc_orifice_root(1e8, lam) / std::sqrt(1e8), 1.0, 1e-6);
  // Monotonic: flow always runs from high to low pressure.
  double last = -1e300;
  for (double dp = -2e6; dp <= 2e6; dp += 1e3) {
    const double r = calc_orifice_root(dp, lam);
    EXPECT_GT(r, last);
    last = r;
  }
}

TEST(Hydraulics, SmallMotionFrequencyIsTheOilSpringOnTheArm) {
  // Valve held closed (K = 0), no leakage: the arm on two oil columns oscillates at
  // omega_h = sqrt(4 beta D^2 / (V_t J)) (Merritt 1967) with J the rigid arm's inertia, about the
  // angle where the oil spring k_h = 4 beta D^2 / V_t balances the initial pressure step.
  ModelSpec s = stiff_arm();
  s.segments = 2;
  s.joints.stiffness *= 1e3;  // the beam as one rigid body (its mode far above omega_h)
  s.hydraulics.enabled = true;
  s.hydraulics.pressure_gain = 0.0;
  s.hydraulics.leakage = 0.0;
  s.simulation.integrator = Integrator::kCvodeDense;
  const Model m = make_model(s);
  const BatchModel bm = one_lane(m);
  BatchState st = make_state(bm);
  const double dp = 0.1e6;  // Pa, on chamber a
  st.z[bm.layout.pressure] += dp / kPressureUnit;
  const auto& h = s.hydraulics;
  const double k_h = 4.0 * h.bulk_modulus * h.displacement * h.displacement / (2.0 * h.chamber_volume);
  const double centre = h.displacement * dp / k_h;  // rad
  CvodeBatch cv(bm, Integrator::kCvodeDense);
  std::vector<double> crossings;  // times the hub angle passes the centre, interpolated
  double x_prev = -centre;
  for (int k = 0; k < 1500; ++k) {
    cv.advance(st, 1e-3);
    st.t += 1e-3;
    const double x = st.q[0] - centre;
    if ((x > 0) != (x_prev > 0)) crossings.push_back(st.t - 1e-3 * x / (x - x_prev));
    x_prev = x;
  }
  ASSERT_EQ(st.status[0], LaneStatus::kOk);
  ASSERT_GE(crossings.size(), 6u);
  const double period = 2.0 * (crossings.back() - crossings.front()) / (crossings.size() - 1);
  const double expected = calc_hydraulic_frequency(h, m.rigid_inertia);
  EXPECT_NEAR(2.0 * M_PI / period, expected, 2e-3 * expected);
}

// Tip deflection of the first 6 s of a 0.5 rad move on the hydraulic rig (kd 2e4) with `set`.
std::vector<double> hydraulic_tip(bool hydraulic, double valve_hz, double gain, Integrator integrator = Integrator::kRk4) {
  ModelSpec s = test::rig_spec(0.5, 3.0);
  s.controller.kd = 2.0e4;
  s.hydraulics.enabled = hydraulic;
  s.hydraulics.valve_frequency = valve_hz;
  s.hydraulics.pressure_gain = gain;
  s.simulation.integrator = integrator;
  return test::run_one(make_model(s)).traces[0].tip_deflection;
}

TEST(Hydraulics, ActuatorTendsToTheIdealTorqueSourceAsValveAndLoopGetFast) {
  // The torque loop's lag and its damping D^2 p_s / (K K_q) vanish as K and the valve grow.
  const auto ideal = hydraulic_tip(false, 200, 5);
  const double slow = rms_diff(hydraulic_tip(true, 200, 5), ideal);
  const double fast = rms_diff(hydraulic_tip(true, 2000, 50), ideal);
  const double faster = rms_diff(hydraulic_tip(true, 20000, 500), ideal);
  EXPECT_GT(slow, 0.02);  // m: the default actuator visibly changes the response
  EXPECT_LT(fast, 0.2 * slow);
  EXPECT_LT(faster, 0.2 * fast);
}

TEST(Hydraulics, FixedStepIntegratorsAgreeWithCvodeOnTheStiffOil) {
  const auto cvode = hydraulic_tip(true, 200, 5, Integrator::kCvodeDense);
  EXPECT_LT(rms_diff(hydraulic_tip(true, 200, 5, Integrator::kRk4), cvode), 1e-5);     // m
  EXPECT_LT(rms_diff(hydraulic_tip(true, 200, 5, Integrator::kSdirk2), cvode), 1e-4);  // m
  EXPECT_LT(rms_diff(hydraulic_tip(true, 200, 5, Integrator::kMidpoint), cvode), 1e-4);  // m
}

// The highest chamber pressure while a demand beyond the stall torque pushes an arm that can hardly move.
double peak_pressure(double relief) {
  ModelSpec s = stiff_arm();
  s.payload_mass = 1e6;
  s.hydraulics.enabled = true;
  s.hydraulics.relief_pressure = relief;
  const Model m = make_model(s);
  const BatchModel bm = one_lane(m);
  BatchState st = make_state(bm);
  Workspace ws = make_workspace(bm);
  st.tau[0] = 1.0e5;  // N m, twice the stall torque D (p_s - p_t)
  double peak = 0.0;
  for (int k = 0; k < 5000; ++k) {
    step_sdirk2(bm, st, ws, 1e-4);
    peak = std::max(peak, st.z[bm.layout.pressure] * kPressureUnit);
  }
  return peak;
}

TEST(Hydraulics, ReliefValveCapsTheChamberPressure) {
  const double ps = HydraulicSpec{}.supply_pressure;
  EXPECT_GT(peak_pressure(0.0), 0.95 * ps);  // relief at 1.1 p_s: the supply is the limit
  const double capped = peak_pressure(12e6);
  // Stalled, the valve's inflow kv root(p_s - p) leaves through the relief, k_r (p - p_r): p settles
  // where the two meet, above p_r by the valve flow over the relief gain (rated flow at 1.1 p_r).
  const HydraulicSpec h;
  const double kv = calc_valve_coefficient(h), kr = calc_rated_flow(h) / (0.1 * 12e6);
  double p = 12e6;
  for (int i = 0; i < 50; ++i) p = 12e6 + kv * calc_orifice_root(ps - p, h.laminar_drop) / kr;
  EXPECT_GT(capped, 12e6);
  EXPECT_LT(capped, 1.05 * p);  // the peak of the first transient
}

TEST(Hydraulics, ValveCoefficientAndDisplacementFollowTheirPhysicalForms) {
  // The rated defaults: k_v = Q_r / root(dp_r) with the laminar core, a little above Q_r / sqrt(dp_r).
  const HydraulicSpec rated;
  EXPECT_DOUBLE_EQ(calc_valve_coefficient(rated), 8.554104586691028e-07);
  EXPECT_GT(calc_valve_coefficient(rated), 1.6e-3 / std::sqrt(3.5e6));
  EXPECT_EQ(calc_rated_flow(rated), 1.6e-3);
  EXPECT_EQ(calc_displacement(rated), 2.5e-3);
  // A servo valve's land: C_d 0.61, a 20 mm wide port (m^2 of opening per m of travel), 1 mm stroke,
  // 850 kg/m^3 oil; a 125 cm^2 piston on a 0.2 m pinion.
  HydraulicSpec h;
  h.discharge_coefficient = 0.61;
  h.port_width = 0.02;
  h.spool_stroke = 1.0e-3;
  h.oil_density = 850.0;
  h.piston_area = 0.0125;
  h.pinion_radius = 0.2;
  const double kv = 0.61 * 0.02 * 1.0e-3 * std::sqrt(2.0 / 850.0);
  EXPECT_DOUBLE_EQ(calc_valve_coefficient(h), kv);
  EXPECT_NEAR(calc_valve_coefficient(h), 5.9178e-7, 1e-10);
  EXPECT_DOUBLE_EQ(calc_rated_flow(h), kv * calc_orifice_root(3.5e6, 1e5));  // sized at the default rated drop
  EXPECT_DOUBLE_EQ(calc_displacement(h), 2.5e-3);
  // The lanes, the loop damping and the oil spring all take them from there.
  ModelSpec s = test::rig_spec();
  s.hydraulics = h;
  s.hydraulics.enabled = true;
  s.hydraulics.pinion_radius = 0.1;  // D = 1.25e-3
  const Model m = make_model(s);
  const LaneDrive p = make_lane_drive(m);
  EXPECT_DOUBLE_EQ(p.kv, kv);
  EXPECT_DOUBLE_EQ(p.D, 1.25e-3);
  EXPECT_DOUBLE_EQ(p.kr, calc_rated_flow(h) / (0.1 * 1.1 * 21e6));
  HydraulicSpec rated_equal = rated;
  rated_equal.displacement = 1.25e-3;
  rated_equal.rated_flow = calc_rated_flow(h);
  EXPECT_DOUBLE_EQ(calc_hydraulic_frequency(s.hydraulics, 100.0), calc_hydraulic_frequency(rated_equal, 100.0));
  EXPECT_NEAR(calc_hydraulic_damping(s.hydraulics), calc_hydraulic_damping(rated_equal),
              1e-12 * calc_hydraulic_damping(rated_equal));
  EXPECT_NEAR(calc_hydraulic_frequency(s.hydraulics, 100.0), std::sqrt(4.0 * 1.4e9 * 1.25e-3 * 1.25e-3 / (9e-3 * 100.0)),
              1e-9);
}

TEST(Hydraulics, PhysicalFormEqualToTheRatedDefaultsRunsBitIdentically) {
  // Values whose products are exact in binary: C_d = 1/2, rho = 2048 (sqrt(2 / rho) = 1/32),
  // x_max = 2^-10 m, w = k_v 2^16 m, so C_d w x_max sqrt(2 / rho) = k_v; A = 4 D, r = 1/4 m.
  ModelSpec rated = test::rig_spec(0.5, 1.0);
  rated.hydraulics.enabled = true;
  rated.hydraulics.relief_pressure = 18e6;  // the relief's sizing in the loop too
  const double kv = calc_valve_coefficient(rated.hydraulics);
  ModelSpec physical = rated;
  auto& h = physical.hydraulics;
  h.discharge_coefficient = 0.5;
  h.oil_density = 2048.0;
  h.spool_stroke = std::ldexp(1.0, -10);
  h.port_width = std::ldexp(kv, 16);
  h.piston_area = 4.0 * rated.hydraulics.displacement;
  h.pinion_radius = 0.25;
  h.displacement = 1.0;  // not used once the physical form is given
  h.rated_flow = 1.0;
  ASSERT_EQ(calc_valve_coefficient(h), kv);
  ASSERT_EQ(calc_rated_flow(h), rated.hydraulics.rated_flow);
  ASSERT_EQ(calc_displacement(h), 2.5e-3);
  const BatchRun a = test::run_one(make_model(rated)), b = test::run_one(make_model(physical));
  ASSERT_GT(a.traces[0].t.size(), 3000u);
  EXPECT_EQ(a.traces[0].hub_angle, b.traces[0].hub_angle);
  EXPECT_EQ(a.traces[0].torque, b.traces[0].torque);
  EXPECT_EQ(a.traces[0].tip_deflection, b.traces[0].tip_deflection);
  ASSERT_EQ(a.traces[0].extra.size(), b.traces[0].extra.size());
  for (std::size_t c = 0; c < a.traces[0].extra.size(); ++c)
    EXPECT_EQ(a.traces[0].extra[c].second, b.traces[0].extra[c].second) << a.traces[0].extra[c].first;
  EXPECT_GT(std::abs(a.traces[0].hub_angle.back()), 0.4);  // the arm moved: a real run
}

TEST(DriveTrain, TransmitsNothingInsideTheFreePlayAndNeverPulls) {
  LaneDrive p;
  p.k = 1e6;
  p.c = 1e3;
  p.b = 0.01;
  EXPECT_EQ(calc_transmission_torque(p, 0.009, 5.0), 0.0);
  EXPECT_EQ(calc_transmission_torque(p, -0.009, -5.0), 0.0);
  EXPECT_NEAR(calc_transmission_torque(p, 0.011, 0.0), 1e6 * 0.001, 1e-6);
  EXPECT_EQ(calc_transmission_torque(p, 0.011, -10.0), 0.0);  // separating teeth do not pull
  EXPECT_NEAR(calc_transmission_torque(p, -0.012, 0.0), -1e6 * 0.002, 1e-6);
}

TEST(DriveTrain, ClosingDampingActsOnlyWhileTheTwistGrows) {
  // drive.closing_damping: c e' only while |e| grows (the teeth closing); the spring alone as they part.
  LaneDrive p;
  p.k = 1e6;
  p.c = 1e3;
  p.b = 0.01;
  p.closing = true;
  EXPECT_NEAR(calc_transmission_torque(p, 0.011, 5.0), 1e6 * 0.001 + 1e3 * 5.0, 1e-6);   // closing
  EXPECT_NEAR(calc_transmission_torque(p, 0.011, -0.5), 1e6 * 0.001, 1e-6);             // parting: no drag
  EXPECT_NEAR(calc_transmission_torque(p, -0.012, 0.5), -1e6 * 0.002, 1e-6);            // parting, other flank
  EXPECT_NEAR(calc_transmission_torque(p, -0.012, -2.0), -1e6 * 0.002 - 1e3 * 2.0, 1e-6);  // closing
  EXPECT_EQ(calc_transmission_tangent(p, 0.011, -0.5).damping, 0.0);
  EXPECT_EQ(calc_transmission_tangent(p, 0.011, 0.5).damping, 1e3);
  p.b = 0.0;  // without free play: the twist itself
  EXPECT_NEAR(calc_transmission_torque(p, 0.001, -3.0), 1e3, 1e-9);
  EXPECT_NEAR(calc_transmission_torque(p, 0.001, 3.0), 1e3 + 3e3, 1e-9);
  p.closing = false;
  EXPECT_NEAR(calc_transmission_torque(p, 0.001, -3.0), 1e3 - 3e3, 1e-9);
}

// Drive train on the stiff arm: steps RK4 at 0.1 ms with the shaft torque demand `demand(t)`;
// calls `sample(st)` every millisecond.
template <class Demand, class Sample>
void run_drive(const ModelSpec& s, double seconds, Demand demand, Sample sample) {
  const Model m = make_model(s);
  const BatchModel bm = one_lane(m);
  BatchState st = make_state(bm);
  Workspace ws = make_workspace(bm);
  const long n = std::lround(seconds / 1e-4);
  for (long k = 0; k < n; ++k) {
    st.t = k * 1e-4;
    st.tau[0] = demand(st.t);
    step_rk4(bm, st, ws, 1e-4);
    if (k % 10 == 9) sample(bm, st);
  }
}

TEST(DriveTrain, BacklashLoopIsAsWideAsTheFreePlay) {
  // A slow sinusoidal torque swings the arm against viscous friction. While the shaft reverses,
  // the twist theta_a / n - theta_h crosses the whole play: it spans [-b, b] plus the elastic twist
  // of the teeth in contact (under the impact when the play closes: within 10 % of b).
  ModelSpec s = stiff_arm();
  s.drive.enabled = true;
  s.drive.backlash = 0.02;  // 2b
  s.drive.stiffness = 1e7;
  s.friction.viscous = 5e3;
  const double amplitude = 2000.0;  // N m
  double lo = 1e9, hi = -1e9, swing = 0.0;
  run_drive(s, 4.0, [&](double t) { return amplitude * std::sin(2.0 * M_PI * 0.5 * t); },
            [&](const BatchModel& bm, const BatchState& st) {
              const double d = st.z[bm.layout.shaft] - st.q[0];
              lo = std::min(lo, d);
              hi = std::max(hi, d);
              swing = std::max(swing, std::abs(st.q[0]));
            });
  const double b = 0.01, elastic = 0.1 * b;
  EXPECT_GT(hi, b);
  EXPECT_LT(hi, b + elastic);
  EXPECT_LT(lo, -b);
  EXPECT_GT(lo, -b - elastic);
  EXPECT_GT(swing, 5.0 * b);  // the arm really moved
}

TEST(DriveTrain, GearMultipliesTorqueByRatioTimesEfficiency) {
  // Steady driving against hub viscous friction: tau_hub = eta n tau_shaft.
  ModelSpec s = stiff_arm();
  s.drive.enabled = true;
  s.drive.ratio = 2.0;
  s.drive.efficiency = 0.8;
  s.friction.viscous = 2e4;
  double tau_hub = 0.0;
  run_drive(s, 8.0, [](double) { return 2.0 * 1000.0; },  // demand at the hub: shaft gets 1000 N m
            [&](const BatchModel& bm, const BatchState& st) {
              compute_actuator_torque(bm, st.q.data(), st.v.data(), st.z.data(), st.tau.data(), &tau_hub);
            });
  EXPECT_NEAR(tau_hub, 0.8 * 2.0 * 1000.0, 1.0);
}

// Chain, shaft and drive-spring energy, J.
double drive_energy(const BatchModel& bm, const BatchState& st, const DriveSpec& d) {
  const double th = st.z[bm.layout.shaft], w = st.z[bm.layout.shaft + 1];
  const double twist = th / d.ratio - st.q[0];
  return calc_kinetic_energy(bm, st.q.data(), st.v.data(), 0) + calc_spring_energy(bm, st.q.data(), 0) +
         0.5 * d.inertia * w * w + 0.5 * d.stiffness * twist * twist + 0.25 * d.cubic_stiffness * std::pow(twist, 4);
}

TEST(DriveTrain, ConservesEnergyWithAllDissipationOff) {
  ModelSpec s = test::rig_spec();
  s.joints.damping = 0.0;
  s.drive.enabled = true;
  s.drive.ratio = 3.0;
  s.drive.stiffness = 2e6;
  s.drive.damping = 0.0;
  s.drive.cubic_stiffness = 1e9;
  const Model m = make_model(s);
  const BatchModel bm = one_lane(m);
  BatchState st = make_state(bm);
  Workspace ws = make_workspace(bm);
  st.z[bm.layout.shaft + 1] = 3.0;  // shaft spinning at 3 rad/s, arm at rest
  const double e0 = drive_energy(bm, st, s.drive);
  for (int k = 0; k < 20000; ++k) step_rk4(bm, st, ws, 1e-4);
  EXPECT_GT(std::abs(st.q[0]), 0.005);  // energy moved into the arm
  EXPECT_NEAR(drive_energy(bm, st, s.drive), e0, 1e-7 * e0);
}

TEST(DriveTrain, TheImplicitMethodsHoldTheGearedRigUnderPdOnAnyChain) {
  // configs/fbtb.yaml through the default drive train (a 2e7 N m/rad mesh): its PD loop through the
  // mesh rings for the whole run. The mesh's hub side is taken linearly implicit
  // (kernel/fixed_step.cpp, set_hub_armature), as the joint springs are; with it explicit the midpoint
  // rule went non-finite at 18 s on the 12-segment chain at the automatic step. 20 s on that chain and
  // on one drawn over 6-32 segments: every fixed-step method finite, its tip within 5 mm RMS of CVODE
  // over the first second (the ringing loop parts the methods' phases later).
  const ModelSpec base = load_model(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb.yaml").spec;
  CounterRng rng(20261204);
  for (int draw = 0; draw < 2; ++draw) {
    ModelSpec s = base;
    s.segments = draw == 0 ? 12 : 6 + static_cast<int>(rng.uniform() * 27.0);
    s.drive.enabled = true;
    s.simulation.duration = 20.0;
    auto run = [&](Integrator i) {
      s.simulation.integrator = i;
      return test::run_one(make_model(s));
    };
    s.simulation.duration = 1.0;
    const std::vector<double> cvode = run(Integrator::kCvodeDense).traces[0].tip_deflection;
    for (Integrator i : {Integrator::kRk4, Integrator::kSdirk2, Integrator::kMidpoint}) {
      s.simulation.duration = 20.0;
      const BatchRun r = run(i);
      EXPECT_EQ(r.status[0], LaneStatus::kOk) << "N = " << s.segments << ", integrator " << integrator_name(i);
      const std::vector<double>& tip = r.traces[0].tip_deflection;
      EXPECT_LT(rms_diff(std::vector<double>(tip.begin(), tip.begin() + cvode.size()), cvode), 5e-3)
          << "N = " << s.segments << ", integrator " << integrator_name(i);
    }
  }
}

TEST(LuGre, SticksBelowAndBreaksAwayAtTheStictionTorque) {
  ModelSpec s = stiff_arm();
  s.friction.model = "lugre";
  s.friction.coulomb = 400.0;
  s.friction.stiction = 600.0;
  s.friction.stribeck_velocity = 0.02;
  const double sigma0 = s.friction.bristle_stiffness;
  // Torque ramp at 100 N m/s; breakaway = the torque when the hub first exceeds 10 mrad/s.
  double breakaway = 0.0, max_stick_rate = 0.0, max_stick_angle = 0.0;
  int sign_changes = 0;
  double last_rate = 0.0;
  run_drive(s, 9.0, [](double t) { return 100.0 * t; }, [&](const BatchModel&, const BatchState& st) {
    const double torque = 100.0 * st.t;
    if (torque < 0.5 * 600.0) {
      max_stick_rate = std::max(max_stick_rate, std::abs(st.v[0]));
      max_stick_angle = std::max(max_stick_angle, std::abs(st.q[0]));
      if (st.v[0] * last_rate < 0.0) ++sign_changes;
      last_rate = st.v[0];
    }
    if (breakaway == 0.0 && st.v[0] > 0.01) breakaway = torque;
  });
  EXPECT_GT(breakaway, 0.9 * 600.0);
  EXPECT_LT(breakaway, 1.1 * 600.0);
  EXPECT_LT(max_stick_rate, 5e-3);  // rad/s: presliding creep only, no chatter while stuck
  EXPECT_LT(max_stick_angle, 3.0 * 600.0 / sigma0);  // presliding: bristle deflection only
  EXPECT_LE(sign_changes, 2);  // the bristles ring out once, then creep one way
}

TEST(DriveTrain, StuckHubTwistsTheHardeningGearUntilItCarriesTheTransmittedTorque) {
  // Open loop: a constant demand tau (output side; the shaft gets tau / n) against LuGre friction that
  // holds the hub (tau far below F_c). Once the transients have died the shaft is at rest, where the
  // efficiency's switch 1/2 (1 + tanh(tau_s omega_a / n)) sits half way, so the shaft's balance
  // tau / n = (tau_s / n) (1/eta + eta) / 2 gives the transmitted torque tau_s = 2 eta tau / (1 + eta^2).
  // The gear then twists to k e + k3 e^3 = tau_s and the bristles carry it, sigma0 z = tau_s.
  ModelSpec s = test::rig_spec();
  s.segments = 1;  // a rigid arm without payload (J = 1135 kg m^2): no beam modes to ring out
  s.payload_mass = s.payload_inertia = 0.0;
  s.drive.enabled = true;
  s.drive.ratio = 2.0;
  s.drive.efficiency = 0.8;
  s.drive.stiffness = 1e5;           // N m/rad
  s.drive.cubic_stiffness = 2.5e10;  // N m/rad^3: k3 e^2 ~ 0.6 k at the twist below
  s.drive.damping = 3.5e3;           // zeta ~ 0.7 for the shaft (n^2 J_a = 20 kg m^2) on the gear spring
  s.friction.model = "lugre";
  s.friction.coulomb = 1000.0;
  s.friction.stiction = 1200.0;
  s.friction.bristle_stiffness = 1e6;
  // N m, 0.2 F_s. Small enough that the efficiency switch, whose slope at rest acts on the shaft as a
  // damper (tau_s / n)^2 (1/eta - eta) / 2, stays within RK4's reach at 0.1 ms.
  const double tau = 250.0;
  double e = 0.0, z = 0.0, rate = 1.0, shaft_rate = 1.0;
  run_drive(s, 8.0, [&](double) { return tau; }, [&](const BatchModel& bm, const BatchState& st) {
    e = st.z[bm.layout.shaft] / s.drive.ratio - st.q[0];
    z = st.z[bm.layout.bristle];
    rate = st.v[0];
    shaft_rate = st.z[bm.layout.shaft + 1];
  });
  const double eta = s.drive.efficiency, k = s.drive.stiffness, k3 = s.drive.cubic_stiffness;
  const double tau_s = 2.0 * eta * tau / (1.0 + eta * eta);
  double e_exact = tau_s / k;  // Newton on k e + k3 e^3 = tau_s
  for (int i = 0; i < 50; ++i) e_exact -= (k * e_exact + k3 * e_exact * e_exact * e_exact - tau_s) / (k + 3 * k3 * e_exact * e_exact);
  EXPECT_LT(std::abs(rate), 1e-10);        // rad/s: stuck
  EXPECT_LT(std::abs(shaft_rate), 1e-10);  // rad/s
  EXPECT_GT(k3 * e_exact * e_exact, 0.5 * k);  // the cubic term matters: a real test of the hardening law
  EXPECT_NEAR(e, e_exact, 1e-9 * e_exact);
  EXPECT_NEAR(k * e + k3 * e * e * e, tau_s, 1e-8 * tau_s);
  EXPECT_NEAR(s.friction.bristle_stiffness * z, tau_s, 1e-8 * tau_s);
  EXPECT_GT(std::abs(tau_s - eta * tau), 0.01 * tau);  // neither the driving nor the driven law alone
}

TEST(DriveConfig, BadValuesNameTheirKey) {
  auto key_of = [](const ModelSpec& s) {
    try {
      make_model(s);
    } catch (const ConfigError& e) {
      return e.key();
    }
    return std::string("(accepted)");
  };
  ModelSpec s = test::rig_spec();
  s.drive.enabled = true;
  s.drive.efficiency = 1.5;
  EXPECT_EQ(key_of(s), "drive.efficiency");
  s = test::rig_spec();
  s.hydraulics.enabled = true;
  s.hydraulics.tank_pressure = 30e6;
  EXPECT_EQ(key_of(s), "hydraulics.tank_pressure");
  s = test::rig_spec();
  s.friction.model = "dahl";
  EXPECT_EQ(key_of(s), "friction.model");
  s = test::rig_spec();
  s.controller.load_signal = "pressure";
  EXPECT_EQ(key_of(s), "controller.load_signal");
}

TEST(DriveConfig, HydraulicRigFileLoads) {
  const Model m = load_model(std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb_hydraulic.yaml");
  EXPECT_TRUE(m.spec.hydraulics.enabled);
  EXPECT_EQ(m.spec.controller.kd, 2.0e4);
  // Oil spring of the whole arm: 3.76 Hz.
  EXPECT_NEAR(calc_hydraulic_frequency(m.spec.hydraulics, m.rigid_inertia) / (2 * M_PI), 3.76, 0.005);
}

}  // namespace
}  // namespace ff
