// arm/: a hydraulic rotary actuator on an arm's joint (joints.NAME.hydraulics, the rig's actuator per
// joint) against other formulations: the oil spring's frequency sqrt(4 beta D^2 / (V_t J)) (Merritt
// eq. 5-82, kernel calc_hydraulic_frequency) from the trace's zero crossings under every integrator; the
// reference rig (kernel/, its own integrator and state layout) on the same rigid hub, trace for trace;
// CVODE against the fixed-step integrators on a two-link arm with a hydraulic shoulder; the actuator
// holding the arm's weight at the start; bad keys named at their lines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "kernel/batch.hpp"
#include "kernel/drive.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"
#include "multibody/modes.hpp"
#include "tests/arm/test_support.hpp"

namespace ff {
namespace {

using test::arm_error;
using test::arm_from;

ArmRun run_one(const ArmModel& m) { return simulate_arms(std::span<const ArmModel>(&m, 1)); }

// A number as YAML, every bit of it.
std::string num(double x) {
  char b[64];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

// A rigid rotor about the vertical z (gravity along the axis: no load) of inertia J about the joint,
// driven by a hydraulic actuator with the given extra keys.
std::string hydraulic_rotor(double J, const std::string& controller, const std::string& hydraulics,
                            const std::string& simulation) {
  return "gravity: [0, 0, -9.81]\n"
         "bodies:\n"
         "  - name: hub\n"
         "    parent: base\n"
         "    mass: 1.0\n"
         "    inertia: {ixx: " + num(J) + ", iyy: " + num(J) + ", izz: " + num(J) +
         "}\n"
         "    joint: {axis: [0, 0, 1]}\n"
         "controller: {rate: 1000}\n"
         "joints:\n"
         "  hub:\n"
         "    controller: " +
         controller + "\n    hydraulics: " + hydraulics + "\nsimulation: " + simulation + "\n";
}

TEST(ArmHydraulics, TheOilSpringRingsAtSqrtOf4BetaD2OverVtJUnderEveryIntegrator) {
  // Valve held closed (K = 0), no leakage: the trapped oil is a spring 2 beta D^2 / V0 on the rotor.
  // Set coasting at 1 mrad/s from the centre, it rings at sqrt(4 beta D^2 / (V_t J)), V_t = 2 V0
  // (27.9 rad/s at the defaults and J = 5000 kg·m²); measured from the zero crossings of q over 2 s.
  const double J = 5000.0;
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_dense", "cvode_klu", "cvode_gmres"}) {
    ArmModel m = arm_from(hydraulic_rotor(J, "{kp: 0}", "{pressure_gain: 0, leakage: 0}",
                                          std::string("{duration: 2, integrator: ") + integ + "}"));
    m.qd0[0] = 1e-3;
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const std::vector<double>& t = run.traces[0].t();
    const std::vector<double>& q = run.traces[0].column("hub.q");
    std::vector<double> crossings;  // linear interpolation between the samples either side
    for (std::size_t k = 1; k + 1 < q.size(); ++k)
      if (q[k] * q[k + 1] < 0.0) crossings.push_back(t[k] + (t[k + 1] - t[k]) * q[k] / (q[k] - q[k + 1]));
    ASSERT_GE(crossings.size(), 10u) << integ;
    const double half_period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
    const double measured = M_PI / half_period;
    const double expected = calc_hydraulic_frequency(m.actuated[0].control.hydraulics, J);
    EXPECT_NEAR(measured, expected, 0.01 * expected) << integ;
    RecordProperty(std::string(integ) + "_relative_error", num(measured / expected - 1.0));
    // The amplitude w0 / omega: the oil spring's energy exchange, no loss with the valve closed.
    const double peak = *std::max_element(q.begin(), q.end());
    EXPECT_NEAR(peak, 1e-3 / expected, 1e-3 * 1e-3 / expected) << integ;
  }
}

// The reference rig (configs/fbtb_hydraulic.yaml) made rigid (segments: 1: hub, beam and payload one
// body), one 0.5 rad move, RK4 at 4 substeps of the 1 ms sample.
YAML::Node rigid_rig_doc() {
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/fbtb_hydraulic.yaml";
  YAML::Node doc = load_yaml_file(path);
  doc["segments"] = 1;
  YAML::Node moves = YAML::Load("[{target: 0.5, hold: 1.0}]");
  doc["trajectory"]["moves"] = moves;
  doc["simulation"]["integrator"] = "rk4";
  doc["simulation"]["substeps"] = 4;
  return doc;
}

TEST(ArmHydraulics, TheClosedLoopModesHoldTheOilSpringAndTheLinearisationPredictsTheRinging) {
  // The valve held closed, no leakage: the linearised loop has the oil spring exactly (undamped), the
  // spool's own pair at 200 Hz with zeta 0.7, and the two conserved quantities (zero eigenvalues).
  const double J = 5000.0;
  const ArmModel closed = arm_from(hydraulic_rotor(J, "{kp: 0}", "{pressure_gain: 0, leakage: 0}", "{duration: 1}"));
  const double wh = calc_hydraulic_frequency(closed.actuated[0].control.hydraulics, J);
  const std::vector<TreeMode> modes = calc_arm_closed_loop_modes(closed, closed.q0);
  ASSERT_EQ(modes.size(), 4u);  // 0, 0, the oil spring's pair, the spool's pair (complex pairs once)
  EXPECT_LT(modes[1].omega_n, 1e-6);
  EXPECT_TRUE(modes[2].oscillatory);
  EXPECT_NEAR(modes[2].omega_n, wh, 1e-6 * wh);
  EXPECT_NEAR(modes[2].zeta, 0.0, 1e-6);
  EXPECT_NEAR(modes[3].omega_n, 2.0 * M_PI * 200.0, 1e-6 * 2.0 * M_PI * 200.0);
  EXPECT_NEAR(modes[3].zeta, 0.7, 1e-9);
  // The loop closed (K = 5, a PD on the valve's command): its slowest oscillatory mode against the
  // simulated ringing after a small kick (zero crossings of q; the decay from successive peaks).
  ArmModel loop = arm_from(hydraulic_rotor(J, "{kp: 2.0e5, kd: 2.0e4}", "{leakage: 0}", "{duration: 3}"));
  const std::vector<TreeMode> loop_modes = calc_arm_closed_loop_modes(loop, loop.q0);  // kept: `ring` points into it
  const TreeMode* ring = nullptr;
  for (const TreeMode& md : loop_modes)
    if (md.oscillatory && md.zeta < 0.5 && !ring) ring = &md;
  ASSERT_NE(ring, nullptr);
  const double w = ring->omega_n, z = ring->zeta, wd = w * std::sqrt(1.0 - z * z);
  loop.qd0[0] = 1e-4;
  const ArmRun run = run_one(loop);
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const std::vector<double>& t = run.traces[0].t();
  const std::vector<double>& q = run.traces[0].column("hub.q");
  std::vector<double> crossings;
  for (std::size_t k = 1; k + 1 < q.size(); ++k)
    if (q[k] * q[k + 1] < 0.0) crossings.push_back(t[k] + (t[k + 1] - t[k]) * q[k] / (q[k] - q[k + 1]));
  ASSERT_GE(crossings.size(), 4u);
  const double measured = M_PI * static_cast<double>(crossings.size() - 1) / (crossings.back() - crossings.front());
  RecordProperty("mode_rad_s", num(wd));
  RecordProperty("measured_rad_s", num(measured));
  RecordProperty("zeta", num(z));
  EXPECT_NEAR(measured, wd, 0.01 * wd);
}

TEST(ArmHydraulics, ARigidHubOnTheActuatorFollowsTheReferenceRigsTraceToRoundOff) {
  const Model rig = parse_model(rigid_rig_doc(), "fbtb_hydraulic.yaml");
  ASSERT_EQ(rig.nseg, 1);
  const BatchModel bm = make_batch(std::span<const Model>(&rig, 1));
  const BatchRun rr = simulate(bm);
  ASSERT_EQ(rr.status[0], LaneStatus::kOk);
  const Trace& rt = rr.traces[0];
  // The same plant as an arm: one revolute joint carrying the rig's body (its inertia about the hub
  // axis, the axis vertical), the rig's PD gains and actuator, the rig's cubic move as a waypoint.
  const double J = rig.body[0].inertia;
  const HydraulicSpec& h = rig.spec.hydraulics;
  const std::string hyd = "{displacement: " + num(h.displacement) + ", chamber_volume: " + num(h.chamber_volume) +
                          ", bulk_modulus: " + num(h.bulk_modulus) + ", supply_pressure: " + num(h.supply_pressure) +
                          ", tank_pressure: " + num(h.tank_pressure) + ", rated_flow: " + num(h.rated_flow) +
                          ", rated_drop: " + num(h.rated_drop) + ", laminar_drop: " + num(h.laminar_drop) +
                          ", leakage: " + num(h.leakage) + ", valve_frequency: " + num(h.valve_frequency) +
                          ", valve_damping: " + num(h.valve_damping) + ", pressure_gain: " + num(h.pressure_gain) + "}";
  std::string text = hydraulic_rotor(J, "{kp: " + num(rig.spec.controller.kp) + ", kd: " + num(rig.spec.controller.kd) + "}",
                                     hyd, "{duration: " + num(rig.duration) + ", integrator: rk4, substeps: 4}");
  text += "trajectory:\n  shape: cubic\n  waypoints:\n    - {time: 3.0, joints: {hub: 0.5}}\n";
  const ArmModel arm = arm_from(text);
  EXPECT_EQ(arm.tree.body(0).inertia(2, 2), J);
  const ArmRun ar = run_one(arm);
  ASSERT_EQ(ar.status[0], LaneStatus::kOk);
  const ArmTrace& at = ar.traces[0];
  ASSERT_EQ(at.t().size(), rt.t.size());
  double dq = 0.0, dtau = 0.0, dp = 0.0, peak_tau = 0.0;
  const std::vector<double>& pa = rt.extra.at(1).second;
  ASSERT_EQ(rt.extra.at(1).first, "pressure_a");
  for (std::size_t k = 0; k < rt.t.size(); ++k) {
    dq = std::max(dq, std::abs(at.column("hub.q")[k] - rt.hub_angle[k]));
    dtau = std::max(dtau, std::abs(at.column("hub.torque")[k] - rt.torque[k]));
    dp = std::max(dp, std::abs(at.column("hub.pressure_a")[k] - pa[k]));
    peak_tau = std::max(peak_tau, std::abs(rt.torque[k]));
  }
  RecordProperty("hub_angle_difference_rad", num(dq));
  RecordProperty("torque_difference_Nm", num(dtau));
  EXPECT_GT(peak_tau, 1e3);  // the move loads the actuator
  EXPECT_NEAR(rt.hub_angle.back(), 0.5, 5e-3);
  EXPECT_LT(dq, 1e-9);
  EXPECT_LT(dtau, 1e-6 * peak_tau);
  EXPECT_LT(dp, 1e-6 * 21e6);
}

// configs/hydraulic_arm.yaml: a two-link arm in the vertical plane, the shoulder hydraulic.
ArmModel hydraulic_arm(const std::string& integrator, double duration, bool tight = false, bool leak = true) {
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/hydraulic_arm.yaml";
  YAML::Node doc = load_yaml_file(path);
  if (!leak) {  // and held where it starts
    doc["joints"]["shoulder"]["hydraulics"]["leakage"] = 0.0;
    doc["trajectory"].remove("waypoints");
  }
  doc["simulation"]["integrator"] = integrator;
  doc["simulation"]["duration"] = duration;
  if (tight) doc["simulation"]["rtol"] = 1e-10, doc["simulation"]["atol"] = 1e-12;
  return parse_arm(doc, path);
}

TEST(ArmHydraulics, TheFixedStepIntegratorsFollowCvodeOnATwoLinkArmWithAHydraulicShoulder) {
  const ArmRun ref = run_one(hydraulic_arm("cvode_dense", 2.5, true));
  ASSERT_EQ(ref.status[0], LaneStatus::kOk);
  const ArmTrace& rt = ref.traces[0];
  for (const char* integ : {"rk4", "sdirk2", "midpoint", "cvode_klu", "cvode_gmres"}) {
    const ArmRun r = run_one(hydraulic_arm(integ, 2.5));
    ASSERT_EQ(r.status[0], LaneStatus::kOk) << integ;
    double dq = 0.0, dp = 0.0;
    for (std::size_t k = 0; k < rt.t().size(); ++k) {
      for (const char* c : {"shoulder.q", "elbow.q"})
        dq = std::max(dq, std::abs(r.traces[0].column(c)[k] - rt.column(c)[k]));
      dp = std::max(dp, std::abs(r.traces[0].column("shoulder.pressure_a")[k] - rt.column("shoulder.pressure_a")[k]));
    }
    RecordProperty(std::string(integ) + "_joint_error_rad", num(dq));
    RecordProperty(std::string(integ) + "_pressure_error_Pa", num(dp));
    // RK4 and CVODE at their tolerance agree closely; the implicit pair is second order at 0.5 ms.
    const bool second_order = std::string(integ) == "sdirk2" || std::string(integ) == "midpoint";
    EXPECT_LT(dq, second_order ? 1e-5 : 1e-7) << integ;
    EXPECT_LT(dp, second_order ? 2e4 : 2e2) << integ;
  }
}

TEST(ArmHydraulics, AVariantGivesTheSameBitsAloneAndInAnyLaneOfABatch) {
  // Three actuators (loop gain, supply, chamber volume) on the two-link arm, alone and as lanes 0..2 and
  // in reverse, under each integrator: the actuators' states are per lane, so the bits are.
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_dense", "cvode_klu", "cvode_gmres"}) {
    std::vector<ArmModel> lanes;
    const double gains[] = {2.0, 5.0, 9.0}, supplies[] = {21e6, 18e6, 25e6}, volumes[] = {5e-4, 4e-4, 6e-4};
    for (int v = 0; v < 3; ++v) {
      const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/hydraulic_arm.yaml";
      YAML::Node doc = load_yaml_file(path);
      YAML::Node h = doc["joints"]["shoulder"]["hydraulics"];
      h["pressure_gain"] = gains[v];
      h["supply_pressure"] = supplies[v];
      h["chamber_volume"] = volumes[v];
      doc["simulation"]["integrator"] = integ;
      doc["simulation"]["duration"] = 0.4;
      doc["simulation"]["substeps"] = 3;
      doc["trajectory"]["waypoints"][0]["time"] = 0.3;
      lanes.push_back(parse_arm(doc, path));
    }
    const ArmRun together = simulate_arms(lanes);
    std::vector<ArmModel> reversed(lanes.rbegin(), lanes.rend());
    const ArmRun back = simulate_arms(reversed);
    for (std::size_t l = 0; l < lanes.size(); ++l) {
      ASSERT_EQ(together.status[l], LaneStatus::kOk) << integ << " lane " << l;
      EXPECT_EQ(run_one(lanes[l]).traces[0].columns, together.traces[l].columns) << integ << " lane " << l;
      EXPECT_EQ(back.traces[lanes.size() - 1 - l].columns, together.traces[l].columns) << integ << " lane " << l;
    }
    EXPECT_NE(together.traces[0].column("shoulder.pressure_a"), together.traces[1].column("shoulder.pressure_a"));
  }
}

TEST(ArmHydraulics, TheActuatorHoldsTheArmsWeightFromTheStartAndTheJointTorqueIsItsDp) {
  // Without leakage (which the proportional torque loop answers with a small torque error, and the
  // arm with a slow droop its PD corrects) nothing moves: the chambers carry the load exactly.
  const ArmModel m = hydraulic_arm("rk4", 0.5, false, false);
  const ActuatedJoint& shoulder = m.actuated.at(0);
  ASSERT_TRUE(shoulder.control.hydraulics.enabled);
  // The static load at q = 0 (links level): m g x_com of both links about the shoulder.
  const double load = 9.81 * (60.0 * 0.75 + 25.0 * (1.5 + 0.7));
  EXPECT_NEAR(shoulder.hold_torque, load, 1e-9 * load);
  const auto [pa, pb] = calc_initial_pressures(shoulder);
  EXPECT_NEAR(calc_displacement(shoulder.control.hydraulics) * (pa - pb), load, 1e-9 * load);
  EXPECT_DOUBLE_EQ(0.5 * (pa + pb), 0.5 * (21e6 + 0.2e6));
  const ArmRun run = run_one(m);
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const ArmTrace& tr = run.traces[0];
  EXPECT_NEAR(tr.column("shoulder.torque")[0], load, 1e-9 * load);
  EXPECT_DOUBLE_EQ(tr.column("shoulder.pressure_a")[0], pa);  // through the stored MPa
  EXPECT_DOUBLE_EQ(tr.column("shoulder.pressure_b")[0], pb);
  // At rest: no jump at t = 0 (the gravity compensation commands the load the chambers carry).
  double moved = 0.0, dp = 0.0;
  for (std::size_t k = 0; k < tr.t().size(); ++k) {
    for (const char* c : {"shoulder.q", "elbow.q"}) moved = std::max(moved, std::abs(tr.column(c)[k]));
    dp = std::max(dp, std::abs(tr.column("shoulder.pressure_a")[k] - tr.column("shoulder.pressure_b")[k] - (pa - pb)));
  }
  EXPECT_LT(moved, 1e-12);
  EXPECT_LT(dp, 1e-9 * (pa - pb));
  // The electric elbow has no pressure columns.
  EXPECT_THROW(tr.column("elbow.pressure_a"), std::out_of_range);
  // A torque offset on the hydraulic joint is a load on top: the chambers carry it too, the arm still at rest.
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/hydraulic_arm.yaml";
  YAML::Node doc = load_yaml_file(path);
  doc["joints"]["shoulder"]["hydraulics"]["leakage"] = 0.0;
  doc["joints"]["shoulder"]["torque_offset"] = 150.0;
  doc["joints"]["shoulder"]["controller"]["ki"] = 0.0;
  doc["trajectory"].remove("waypoints");
  doc["simulation"]["duration"] = 0.5;
  const ArmModel offset = parse_arm(doc, path);
  EXPECT_NEAR(offset.actuated.at(0).hold_torque, load + 150.0, 1e-9 * load);
  const ArmRun held = run_one(offset);
  ASSERT_EQ(held.status[0], LaneStatus::kOk);
  // The PD commands the gravity load only: the valve loop pulls the torque to the command, and the
  // joint sags until kp e makes up the offset: e = 150 / kp.
  EXPECT_NEAR(held.traces[0].column("shoulder.q").back(), -150.0 / 2.0e4, 2e-4);
}

TEST(ArmHydraulics, ABadKeyOrValueIsNamedAtItsLineAndKey) {
  const std::string sim = "{duration: 0.1}";
  EXPECT_EQ(arm_error(hydraulic_rotor(10.0, "{kp: 1}", "{supply_pressure: -1}", sim)),
            "arm.yaml:12: joints.hub.hydraulics.supply_pressure: must be > 0, got -1");
  EXPECT_EQ(arm_error(hydraulic_rotor(10.0, "{kp: 1}", "{bulk_modulus: 1.4e9, suply_pressure: 2e7}", sim)),
            "arm.yaml:12: joints.hub.hydraulics.suply_pressure: unknown key (did you mean `supply_pressure`?)");
  EXPECT_EQ(arm_error(hydraulic_rotor(10.0, "{kp: 1}", "{tank_pressure: 3.0e7}", sim)),
            "arm.yaml:12: joints.hub.hydraulics.tank_pressure: must be below hydraulics.supply_pressure");
  const std::string forms = arm_error(hydraulic_rotor(10.0, "{kp: 1}", "{piston_area: 0.01, displacement: 2e-3}", sim));
  EXPECT_EQ(forms.rfind("arm.yaml:12: joints.hub.hydraulics.piston_area: given with hydraulics.displacement", 0), 0u)
      << forms;
  const std::string both = arm_error(hydraulic_rotor(10.0, "{kp: 1}", "{}\n    drive: {ratio: 10}", sim));
  EXPECT_NE(both.find("joints.hub.hydraulics: a joint has either a compliant drive train"), std::string::npos) << both;
  // A load the actuator cannot carry at the start: a gravity pendulum of 1000 kg at 1 m on 2.5e-4 m^3/rad.
  std::string heavy = hydraulic_rotor(10.0, "{kp: 1}", "{displacement: 2.5e-4}", sim);
  heavy.replace(heavy.find("mass: 1.0"), 9, "mass: 1000.0\n    com: [1.0, 0, 0]");
  heavy.replace(heavy.find("axis: [0, 0, 1]"), 15, "axis: [0, 1, 0]");
  const std::string cannot = arm_error(heavy);
  EXPECT_NE(cannot.find("joints.hub.hydraulics: the actuator cannot hold the joint at the start"), std::string::npos)
      << cannot;
  std::vector<std::string> keys;
  for (const KeyDoc& k : arm_yaml_keys()) keys.push_back(k.key);
  for (const Field<HydraulicSpec>& f : hydraulic_fields())
    EXPECT_NE(std::find(keys.begin(), keys.end(), std::string("joints.NAME.hydraulics.") + f.key), keys.end()) << f.key;
}

}  // namespace
}  // namespace ff
