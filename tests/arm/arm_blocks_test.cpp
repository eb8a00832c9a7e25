// arm/: the reference rig's hub blocks on an arm's actuated joints, against closed forms: a coasting
// joint's viscous friction decays its rate as exp(-b t / J) and its Coulomb friction decelerates it at
// Fc / J to a stop at J w0 / Fc; a PD hold against a constant load stops where Coulomb friction allows
// (|kp e - offset| <= Fc); friction never adds energy; the sensors quantise, hold, delay and add noise
// that repeats with the seed; a variant's bits the same in any lane.
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/errors.hpp"
#include "kernel/drive.hpp"
#include "kernel/friction.hpp"
#include "multibody/modes.hpp"
#include "common/random.hpp"
#include "common/yaml_reader.hpp"
#include "tests/arm/test_support.hpp"

namespace ff {
namespace {

using test::arm_error;
using test::arm_from;

// A rotor about the vertical z (gravity along the axis: no load): 1 kg at 0.5 m, izz 0.05 about its
// centre, armature 0.1, so J = 0.05 + 1 * 0.5^2 + 0.1 = 0.4 kg·m².
constexpr double kJ = 0.4;
std::string rotor(const std::string& joint, const std::string& simulation) {
  return R"(gravity: [0, 0, -9.81]
bodies:
  - name: arm
    parent: base
    mass: 1.0
    com: [0.5, 0, 0]
    inertia: {ixx: 0.001, iyy: 0.05, izz: 0.05}
    joint: {type: revolute, axis: [0, 0, 1], armature: 0.1}
controller: {rate: 1000}
joints:
  arm: )" + joint + "\nsimulation: " + simulation + "\n";
}

// A measured value for the test report, to 6 significant digits.
std::string fmt(double x) {
  std::ostringstream o;
  o << std::setprecision(6) << x;
  return o.str();
}

ArmRun run_one(const ArmModel& m) { return simulate_arms(std::span<const ArmModel>(&m, 1)); }

const char* const kIntegrators[] = {"rk4", "midpoint", "sdirk2", "cvode_dense", "cvode_klu", "cvode_gmres"};

// The simulation block for an integrator, CVODE tight (at its default rtol 1e-8 its global error on
// these runs is 3e-6, the same with the tree's own joint damper in place of viscous friction).
std::string sim_with(const char* integ, const std::string& rest) {
  const bool cvode = std::string(integ).starts_with("cvode");
  return "{" + rest + ", integrator: " + integ + (cvode ? ", rtol: 1.0e-11, atol: 1.0e-13}" : "}");
}

TEST(ArmFriction, AFreelyCoastingJointWithViscousFrictionDecaysAsExpOfMinusBtOverJ) {
  // w = w0 exp(-b t / J), q = w0 J / b (1 - exp(-b t / J)); b / J = 0.5 /s.
  const double b = 0.2, w0 = 2.0;
  for (const char* integ : kIntegrators) {
    ArmModel m = arm_from(rotor("{controller: {}, friction: {viscous: 0.2}}", sim_with(integ, "duration: 3.0")));
    m.qd0[0] = w0;
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const ArmTrace& tr = run.traces[0];
    double err_w = 0.0, err_q = 0.0;
    for (std::size_t k = 0; k < tr.t().size(); ++k) {
      const double t = tr.t()[k], decay = std::exp(-b * t / kJ);
      err_w = std::max(err_w, std::abs(tr.column("arm.qd")[k] - w0 * decay));
      err_q = std::max(err_q, std::abs(tr.column("arm.q")[k] - w0 * kJ / b * (1.0 - decay)));
    }
    RecordProperty(std::string(integ) + "_rate_error", fmt(err_w));
    EXPECT_LT(err_w, 5e-8 * w0) << integ;  // every method at its order (h b / J = 5e-4 a step)
    EXPECT_LT(err_q, 1e-6) << integ;
    // Viscous friction is the joint's damper: the same bits as the tree's own (joint.damping) in the
    // fixed-step methods (both implicit with armature gh b in the implicit pair).
    if (!std::string(integ).starts_with("cvode")) {
      ArmModel d = arm_from(rotor("{controller: {}}", sim_with(integ, "duration: 3.0")));
      d.spec.tree.spec.bodies[0].damping = b;
      d = make_arm(d.spec);
      d.qd0[0] = w0;
      EXPECT_EQ(run_one(d).traces[0].column("arm.qd"), tr.column("arm.qd")) << integ;
    }
  }
}

TEST(ArmFriction, ACoastingJointWithCoulombFrictionDeceleratesAtFcOverJToAStopAtJw0OverFc) {
  // Fc / J = 1 rad/s², w0 = 2 rad/s: w = w0 - t until t = 2 s, then at rest at q = J w0^2 / (2 Fc) = 2 rad.
  const double fc = 0.4, w0 = 2.0, t_stop = kJ * w0 / fc, q_stop = kJ * w0 * w0 / (2.0 * fc);
  for (const char* integ : kIntegrators) {
    ArmModel m = arm_from(rotor("{controller: {}, friction: {coulomb: 0.4, smoothing: 1.0e-4}}",
                                sim_with(integ, "duration: 3.0")));
    m.qd0[0] = w0;
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const ArmTrace& tr = run.traces[0];
    double err_w = 0.0;
    for (std::size_t k = 0; k < tr.t().size(); ++k) {
      const double t = tr.t()[k];
      if (t < t_stop - 0.01) err_w = std::max(err_w, std::abs(tr.column("arm.qd")[k] - (w0 - fc / kJ * t)));
      if (t > t_stop + 0.01) {
        EXPECT_LT(std::abs(tr.column("arm.qd")[k]), 1e-6) << integ << " t = " << t;
      }
    }
    RecordProperty(std::string(integ) + "_rate_error", fmt(err_w));
    RecordProperty(std::string(integ) + "_stop_angle_error", fmt(tr.column("arm.q").back() - q_stop));
    EXPECT_LT(err_w, 1e-6) << integ;  // tanh(w / eps) = 1 to 1e-80 while w > 0.01 rad/s
    // The smoothing's error: the last eps of rate is shed over ~ J eps / Fc, O(J eps^2 / Fc) of angle.
    EXPECT_NEAR(tr.column("arm.q").back(), q_stop, 1e-7) << integ;
  }
}

TEST(ArmFriction, APdHoldAgainstATorqueOffsetStopsWhereCoulombFrictionAllows) {
  // kp = 100, offset 2 N·m: without friction the joint settles at q* = -offset / kp = -0.02 rad. With
  // Fc = 0.5 N·m it stops anywhere |kp (0 - q) - offset| <= Fc, q in [-0.025, -0.015], short of q*
  // (approaching from q = 0 with kd = 5: zeta 0.4, one overshoot into the band).
  const double kp = 100.0, offset = 2.0, fc = 0.5;
  const ArmModel free = arm_from(rotor("{controller: {kp: 100, kd: 5}, torque_offset: 2.0}", "{duration: 4.0}"));
  EXPECT_NEAR(run_one(free).traces[0].column("arm.q").back(), -offset / kp, 1e-9);
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_dense"}) {
    const ArmModel m = arm_from(rotor("{controller: {kp: 100, kd: 5}, torque_offset: 2.0, friction: {coulomb: 0.5, smoothing: 1.0e-4}}",
                                      sim_with(integ, "duration: 4.0")));
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const std::vector<double>& q = run.traces[0].column("arm.q");
    const double q_end = q.back();
    RecordProperty(std::string(integ) + "_stop_angle", fmt(q_end));
    EXPECT_LE(std::abs(kp * (0.0 - q_end) - offset), fc) << integ;
    EXPECT_GT(std::abs(q_end + offset / kp), 0.1 * fc / kp) << integ;  // friction, not the PD, holds it
    // At rest: over the last second it creeps by no more than eps atanh(|n| / Fc) a second.
    EXPECT_LT(std::abs(q_end - q[q.size() - 1001]), 1e-4) << integ;
  }
}

TEST(ArmFriction, FrictionNeverAddsEnergy) {
  // The map's power tau_f w <= 0 at every rate, for viscous, Coulomb and Stribeck parts.
  FrictionSpec f;
  f.viscous = 0.05, f.coulomb = 0.3, f.stiction = 0.5, f.stribeck_velocity = 0.1, f.smoothing = 1e-3;
  const FrictionMap map = make_friction_map(f);
  for (double w = -3.0; w <= 3.0; w += 1e-4) EXPECT_LE(calc_friction_torque(map, w) * w, 0.0) << w;
  // A coasting rotor with all three: its kinetic energy never rises from one sample to the next, in
  // every integrator, and it stops.
  for (const char* integ : kIntegrators) {
    ArmModel m = arm_from(rotor("{controller: {}, friction: {viscous: 0.05, coulomb: 0.3, stiction: 0.5, stribeck_velocity: 0.1}}",
                                sim_with(integ, "duration: 4.0")));
    m.qd0[0] = 3.0;
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const std::vector<double>& w = run.traces[0].column("arm.qd");
    double rise = -1.0;
    for (std::size_t k = 1; k < w.size(); ++k) rise = std::max(rise, 0.5 * kJ * (w[k] * w[k] - w[k - 1] * w[k - 1]));
    RecordProperty(std::string(integ) + "_largest_rise_J", fmt(rise));
    EXPECT_LE(rise, 1e-20) << integ;  // CVODE's rate at rest jitters at 1e-15 rad/s
    EXPECT_LT(std::abs(w.back()), 1e-6) << integ;
  }
  // A pendulum (hinge about y, gravity -z) released horizontal: E = J w^2 / 2 - m g l sin q never rises
  // by more than the method's own energy error (the midpoint rule's, at the swing's turning points
  // where friction takes nothing, is 1e-6 J: left out), and falls by joules.
  const std::string text = R"(gravity: [0, 0, -9.81]
bodies:
  - name: arm
    parent: base
    mass: 2.0
    com: [0.5, 0, 0]
    inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01}
    joint: {type: revolute, axis: [0, 1, 0], armature: 0.05}
joints:
  arm: {controller: {}, friction: {viscous: 0.05, coulomb: 0.3, stiction: 0.5, stribeck_velocity: 0.1, smoothing: 1.0e-3}}
simulation: )";
  const double J = 0.01 + 2.0 * 0.25 + 0.05, mgl = 2.0 * 9.81 * 0.5;
  for (const char* integ : {"rk4", "sdirk2", "cvode_dense"}) {
    const ArmModel m = arm_from(text + sim_with(integ, "duration: 4.0") + "\n");
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const std::vector<double>&q = run.traces[0].column("arm.q"), &w = run.traces[0].column("arm.qd");
    double rise = -1.0;
    std::vector<double> E(q.size());
    for (std::size_t k = 0; k < q.size(); ++k) E[k] = 0.5 * J * w[k] * w[k] - mgl * std::sin(q[k]);
    for (std::size_t k = 1; k < q.size(); ++k) rise = std::max(rise, E[k] - E[k - 1]);
    RecordProperty(std::string(integ) + "_pendulum_largest_rise_J", fmt(rise));
    RecordProperty(std::string(integ) + "_pendulum_energy_lost_J", fmt(E.front() - E.back()));
    EXPECT_LE(rise, 1e-9) << integ;
    EXPECT_GT(E.front() - E.back(), 1.0) << integ;
  }
}

// A joint tracking a move, its sensors as given.
std::string tracked(const std::string& sensors, const std::string& simulation = "{duration: 2.0}") {
  return rotor("{controller: {kp: 100, kd: 10}, sensors: " + sensors + "}",
               simulation + "\ntrajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 0.5}}");
}

TEST(ArmSensors, TheMeasuredAngleIsAMultipleOfTheResolutionWithinHalfOfItOfTheTruth) {
  const double res = 1e-3, res_rate = 0.01;
  const ArmRun run = run_one(arm_from(tracked("{angle: {resolution: 1.0e-3}, rate: {resolution: 0.01}}")));
  const ArmTrace& tr = run.traces[0];
  int differ = 0;
  for (std::size_t k = 0; k < tr.t().size(); ++k) {
    const double qm = tr.column("arm.q_measured")[k], q = tr.column("arm.q")[k];
    EXPECT_EQ(qm, res * std::nearbyint(qm / res));
    EXPECT_LE(std::abs(qm - q), 0.5 * res * (1 + 1e-12));
    const double wm = tr.column("arm.qd_measured")[k];
    EXPECT_EQ(wm, res_rate * std::nearbyint(wm / res_rate));
    EXPECT_LE(std::abs(wm - tr.column("arm.qd")[k]), 0.5 * res_rate * (1 + 1e-12));
    differ += qm != q;
  }
  EXPECT_GT(differ, 1000);
  EXPECT_NEAR(tr.column("arm.q").back(), 0.5, res);  // the loop holds to within the quantum
}

TEST(ArmSensors, ADelayOfDSamplesShiftsTheMeasuredSignalByExactlyDSamples) {
  const int d = 3;
  const ArmRun run = run_one(arm_from(tracked("{angle: {delay: 3}, rate: {delay: 3}}")));
  const ArmTrace& tr = run.traces[0];
  const std::vector<double>&q = tr.column("arm.q"), &qm = tr.column("arm.q_measured");
  const std::vector<double>&w = tr.column("arm.qd"), &wm = tr.column("arm.qd_measured");
  for (std::size_t k = 0; k < q.size(); ++k) {
    const std::size_t j = k >= d ? k - d : 0;
    ASSERT_EQ(qm[k], q[j]) << k;
    ASSERT_EQ(wm[k], w[j]) << k;
  }
  // A sensor at a quarter of the controller's rate holds each reading four samples.
  const ArmRun held = run_one(arm_from(tracked("{angle: {rate: 250}}")));
  const ArmTrace& th = held.traces[0];
  for (std::size_t k = 0; k < th.t().size(); ++k) ASSERT_EQ(th.column("arm.q_measured")[k], th.column("arm.q")[k / 4 * 4]) << k;
  // The delay costs the loop: it tracks worse than with none.
  const ArmRun none = run_one(arm_from(tracked("{}")));
  auto peak_error = [](const ArmTrace& t) {
    double e = 0.0;
    for (std::size_t k = 0; k < t.t().size(); ++k) e = std::max(e, std::abs(t.column("arm.q")[k] - t.column("arm.ref")[k]));
    return e;
  };
  EXPECT_NE(peak_error(tr), peak_error(none.traces[0]));
  EXPECT_EQ(none.traces[0].column("arm.q_measured"), none.traces[0].column("arm.q"));
}

TEST(ArmSensors, NoiseWithTheSameSeedRepeatsBitForBitAndDiffersWithAnother) {
  const std::string s = "{angle: {noise: 1.0e-3}, rate: {noise: 0.01}}";
  const ArmModel a = arm_from(tracked(s, "{duration: 2.0, seed: 7}"));
  const ArmRun r1 = run_one(a), r2 = run_one(a);
  EXPECT_EQ(r1.traces[0].columns, r2.traces[0].columns);
  const ArmRun r3 = run_one(arm_from(tracked(s, "{duration: 2.0, seed: 8}")));
  EXPECT_NE(r1.traces[0].column("arm.q_measured"), r3.traces[0].column("arm.q_measured"));
  EXPECT_NE(r1.traces[0].column("arm.q"), r3.traces[0].column("arm.q"));  // the loop felt it
  // The noise is the stream (seed, channel 0) at each sample; its moments those of N(0, sigma^2).
  const ArmTrace& tr = r1.traces[0];
  const std::uint64_t key = calc_variant_seed(7, 0);
  double sum = 0.0, sum2 = 0.0;
  const std::size_t n = tr.t().size();
  for (std::size_t k = 0; k < n; ++k) {
    const double e = tr.column("arm.q_measured")[k] - tr.column("arm.q")[k];
    EXPECT_NEAR(e, 1e-3 * CounterRng(key, k).normal(), 1e-15);
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  RecordProperty("angle_noise_sd", fmt(sd));
  EXPECT_NEAR(sd, 1e-3, 0.1e-3);
  EXPECT_NEAR(mean, 0.0, 4.0 * 1e-3 / std::sqrt(static_cast<double>(n)));
}

// Each lane's trace the same bits alone, in a batch, and in the batch reversed.
void expect_same_bits_alone_and_in_any_lane(const std::vector<ArmModel>& lanes, const char* integ) {
  const ArmRun together = simulate_arms(lanes);
  for (std::size_t l = 0; l < lanes.size(); ++l) {
    const ArmRun alone = simulate_arms(std::span<const ArmModel>(&lanes[l], 1));
    EXPECT_EQ(alone.traces[0].columns, together.traces[l].columns) << integ << " lane " << l;
  }
  std::vector<ArmModel> reversed(lanes.rbegin(), lanes.rend());
  const ArmRun back = simulate_arms(reversed);
  for (std::size_t l = 0; l < lanes.size(); ++l)
    EXPECT_EQ(back.traces[lanes.size() - 1 - l].columns, together.traces[l].columns) << integ << " lane " << l;
}

TEST(ArmSimulate, AVariantWithFrictionSensorsAndALoadGivesTheSameBitsAloneAndInAnyLane) {
  for (const char* integ : {"rk4", "sdirk2"}) {
    const std::string sim = std::string("{duration: 1.5, substeps: 8, integrator: ") + integ;
    std::vector<ArmModel> lanes;
    lanes.push_back(arm_from(rotor("{controller: {kp: 100, kd: 10}, friction: {viscous: 0.1, coulomb: 0.3, stiction: 0.4}}",
                                   sim + "}\ntrajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 0.5}}")));
    lanes.push_back(arm_from(rotor("{controller: {kp: 120, kd: 10}, sensors: {angle: {noise: 1.0e-3, delay: 2}, rate: {resolution: 0.01}}}",
                                   sim + ", seed: 3}\ntrajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 0.5}}")));
    lanes.push_back(arm_from(rotor("{controller: {kp: 100, kd: 12}, torque_offset: 1.5}",
                                   sim + "}\ntrajectory:\n  waypoints:\n    - {time: 1.0, joints: {arm: 0.5}}")));
    expect_same_bits_alone_and_in_any_lane(lanes, integ);
  }
}

TEST(ArmYaml, TheJointBlocksAreListedAndTheirErrorsNamedAtTheirLines) {
  std::vector<std::string> keys;
  for (const KeyDoc& k : arm_yaml_keys()) keys.push_back(k.key);
  for (const char* k : {"joints.NAME.torque_offset", "joints.NAME.friction.viscous", "joints.NAME.friction.coulomb",
                        "joints.NAME.friction.stiction", "joints.NAME.friction.stribeck_velocity",
                        "joints.NAME.friction.smoothing", "joints.NAME.sensors.angle.resolution",
                        "joints.NAME.sensors.angle.noise", "joints.NAME.sensors.angle.delay",
                        "joints.NAME.sensors.angle.rate", "joints.NAME.sensors.rate.noise", "simulation.seed"})
    EXPECT_NE(std::find(keys.begin(), keys.end(), k), keys.end()) << k;
  const std::string bad_stiction = arm_error(rotor("{controller: {}, friction: {coulomb: 0.5, stiction: 0.2}}", "{duration: 1}"));
  EXPECT_NE(bad_stiction.find("joints.arm.friction.stiction"), std::string::npos) << bad_stiction;
  const std::string misspelt = arm_error(rotor("{controller: {}, friction: {colomb: 0.5}}", "{duration: 1}"));
  EXPECT_NE(misspelt.find("colomb"), std::string::npos) << misspelt;
  const std::string rate = arm_error(rotor("{controller: {}, sensors: {angle: {rate: 300}}}", "{duration: 1}"));
  EXPECT_NE(rate.find("joints.arm.sensors.angle.rate"), std::string::npos) << rate;
  const std::string neg = arm_error(rotor("{controller: {}, sensors: {rate: {noise: -1}}}", "{duration: 1}"));
  EXPECT_NE(neg.find("arm.yaml:11: joints.arm.sensors.rate.noise"), std::string::npos) << neg;
  const std::string seed = arm_error(rotor("{controller: {}}", "{duration: 1, seed: 1.5}"));
  EXPECT_NE(seed.find("simulation.seed"), std::string::npos) << seed;
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

// A joint with a compliant drive (insert_drive_train): a 2 kg bob 0.5 m out on a hinge about y, its
// rotor of 0.01 kg·m² through a 100:1 gear (reflected 100 kg·m²) and a drive stiffness k = 2e4 N·m/rad.
std::string drive_arm(const std::string& extra = "") {
  return "gravity: [0, 0, -9.81]\n"
         "bodies:\n"
         "  - name: arm\n"
         "    parent: base\n"
         "    mass: 2.0\n"
         "    com: [0.5, 0, 0]\n"
         "    inertia: {ixx: 0.001, iyy: 0.01, izz: 0.01}\n"
         "    joint: {axis: [0, 1, 0]}\n"
         "joints:\n"
         "  arm:\n"
         "    controller: {kp: 4.0e4, kd: 2.0e3, gravity_compensation: 1}\n"
         "    drive: {rotor_inertia: 0.01, ratio: 100, stiffness: 2.0e4, damping: 0}\n" +
         extra + "simulation: {duration: 0.5}\n";
}

TEST(ArmDrive, TheDrivesTwoMassModeIsAtSqrtOfKOverTheReducedInertiaAndTheLinkSagsByTheLoadOverK) {
  const ArmModel m = test::arm_from(drive_arm());
  ASSERT_EQ(m.tree.nv(), 2);
  const int rotor = m.spec.tree.dof_index.at("arm"), twist = m.spec.tree.dof_index.at("arm.twist");
  EXPECT_EQ(m.actuated.at(0).dof, rotor);
  EXPECT_EQ(m.tree.body(0).armature, 100.0 * 100.0 * 0.01);
  // Free-free (no controller, no gravity stiffness at q = 0): w^2 = k (1/J_r + 1/J_l).
  const double Jr = 100.0, Jl = 2.0 * 0.25 + 0.01, k = 2.0e4;
  const std::vector<TreeMode> modes = calc_tree_modes(m.tree, Eigen::VectorXd::Zero(2));
  double w = 0.0;
  for (const TreeMode& md : modes) w = std::max(w, md.omega_n);
  EXPECT_NEAR(w, std::sqrt(k * (1.0 / Jr + 1.0 / Jl)), 1e-9 * w);
  // The start: the rotor held at 0, the link twisted by its weight's moment over k (small angles:
  // k q = m g l cos q, q > 0 about +y is down).
  const double q = m.q0[twist];
  EXPECT_NEAR(k * q, 2.0 * 9.81 * 0.5 * std::cos(q), 1e-8);
  EXPECT_EQ(m.q0[rotor], 0.0);
  // The controller's gravity compensation (the rigid arm's) holds the rotor; the link stays twisted.
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1));
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  EXPECT_NEAR(run.traces[0].column("arm.q").back(), 0.0, 1e-6);
}

TEST(ArmDrive, ABadDriveIsNamedAtItsKey) {
  std::string text = drive_arm();
  text.replace(text.find("ratio: 100"), 10, "ratio: 0");
  const std::string error = test::arm_error(text);
  EXPECT_EQ(error.rfind("arm.yaml:12: joints.arm.drive.ratio: must be > 0", 0), 0u) << error;
}

}  // namespace
}  // namespace ff

namespace ff {
namespace {

// drive_arm with the drive's law given (and damped), run for `duration` with `integ`.
std::string nonlinear_drive_arm(const std::string& drive, const char* integ, double duration) {
  std::string text = drive_arm();
  text.replace(text.find("    drive: {"), std::string::npos,
               "    drive: {rotor_inertia: 0.01, ratio: 100, stiffness: 2.0e4, damping: 100" + drive + "}\n"
               "tool: {body: arm, point: [1.0, 0, 0]}\n"
               "simulation: " + sim_with(integ, "duration: " + std::to_string(duration)) + "\n");
  return text;
}

// The link's angle from the tool point (1 m out along the link's x, hinge about y: x = cos, z = -sin).
double link_angle(const ArmTrace& tr, std::size_t k) { return std::atan2(-tr.column("tool.z")[k], tr.column("tool.x")[k]); }

TEST(ArmDrive, ALinearLawThroughTheTransmissionFollowsTheTreesOwnSpring) {
  // A lane beside one with backlash takes the transmission's law (b = 0, k3 = 0, eta = 1): T = k e + c ė
  // at the twist instead of the tree's spring and damper, another code path to the same motion.
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_dense"}) {
    std::vector<ArmModel> lanes{arm_from(nonlinear_drive_arm("", integ, 0.5)),
                                arm_from(nonlinear_drive_arm(", backlash: 1.0e-3", integ, 0.5))};
    // A move, so that the twist works both ways.
    for (ArmModel& m : lanes) m.qd0[static_cast<std::size_t>(m.actuated[0].dof)] = 0.5;
    const ArmRun both = simulate_arms(lanes), alone = run_one(lanes[0]);
    ASSERT_EQ(both.status[0], LaneStatus::kOk) << integ;
    double err = 0.0;
    for (std::size_t k = 0; k < alone.traces[0].t().size(); ++k)
      err = std::max(err, std::abs(link_angle(both.traces[0], k) - link_angle(alone.traces[0], k)));
    RecordProperty(std::string(integ) + "_link_angle_difference", fmt(err));
    EXPECT_LT(err, std::string(integ).starts_with("cvode") ? 1e-9 : 1e-12) << integ;
    EXPECT_GT(std::abs(link_angle(both.traces[1], alone.traces[0].t().size() - 1) -
                       link_angle(alone.traces[0], alone.traces[0].t().size() - 1)), 1e-4) << integ;
  }
}

TEST(ArmDrive, AHeldLoadSitsHalfTheBacklashFurtherTwisted) {
  // The rotor held at 0 by the PD with gravity compensation; the link hangs on the teeth: in contact at
  // e = t - b, k e = m g l cos(q_r + t) (b = backlash / 2 = 5 mrad; without backlash t = 4.9 mrad).
  const double k = 2.0e4, mgl = 2.0 * 9.81 * 0.5, b = 5.0e-3;
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_dense"}) {
    const ArmModel m = arm_from(nonlinear_drive_arm(", backlash: 1.0e-2", integ, 2.0));
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const ArmTrace& tr = run.traces[0];
    const std::size_t end = tr.t().size() - 1;
    const double qr = tr.column("arm.q")[end], t = link_angle(tr, end) - qr;
    RecordProperty(std::string(integ) + "_twist", fmt(t));
    EXPECT_NEAR(k * (t - b), mgl * std::cos(qr + t), 1e-6 * mgl) << integ;
    EXPECT_NEAR(t, b + mgl / k, 1e-4 * b) << integ;
  }
}

TEST(ArmDrive, AHeldLoadCostsTheRotorTheMeanOfOneOverEtaAndEta) {
  // At rest the rotor feels the link's torque times (1/eta + eta)/2 (docs/formats.md, drive.efficiency):
  // the PD, its gravity compensation holding the load once, supplies the rest: kp q_r = (f - 1) m g l cos q.
  const double kp = 4.0e4, mgl = 2.0 * 9.81 * 0.5, eta = 0.6, f = 0.5 * (1.0 / eta + eta);
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_dense"}) {
    const ArmModel m = arm_from(nonlinear_drive_arm(", efficiency: 0.6", integ, 2.0));
    const ArmRun run = run_one(m);
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const ArmTrace& tr = run.traces[0];
    const std::size_t end = tr.t().size() - 1;
    const double qr = tr.column("arm.q")[end];
    RecordProperty(std::string(integ) + "_rotor_angle", fmt(qr));
    EXPECT_NEAR(kp * qr, (f - 1.0) * mgl * std::cos(link_angle(tr, end)), 1e-4 * (f - 1.0) * mgl) << integ;
  }
}

TEST(ArmDrive, EfficiencyOnlyTakesEnergyOutsideTheSmoothingBand) {
  // The power into the drive, P (1 - factor(P)) with P the power the rotor passes on: a loss wherever
  // |P| > 1 W, and at most (P* ... 0) of a gain inside, where the smoothed factor crosses 1
  // (s = eta / (1 + eta): P* = atanh(2 s - 1) W).
  for (const double eta : {0.3, 0.6, 0.9, 1.0}) {
    double gain = 0.0;
    for (double P = -20.0; P <= 20.0; P += 1e-3) {
      const double into = P * (1.0 - calc_efficiency_factor(eta, P));
      if (std::abs(P) > 1.0) EXPECT_LE(into, 0.0) << eta << " " << P;
      gain = std::max(gain, into);
    }
    const double p_star = std::atanh(2.0 * eta / (1.0 + eta) - 1.0);
    EXPECT_LE(gain, -p_star * (1.0 - eta)) << eta;
  }
}

TEST(ArmDrive, CubicStiffnessHardensTheSag) {
  // k e + k3 e^3 = m g l cos(q): with k3 = 1e11 the twist sags less than with k alone, to the cubic's root.
  const double k = 2.0e4, k3 = 1.0e11, mgl = 2.0 * 9.81 * 0.5;
  for (const char* integ : {"sdirk2", "cvode_dense"}) {
    const ArmRun run = run_one(arm_from(nonlinear_drive_arm(", cubic_stiffness: 1.0e11", integ, 2.0)));
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const ArmTrace& tr = run.traces[0];
    const std::size_t end = tr.t().size() - 1;
    const double qr = tr.column("arm.q")[end], e = link_angle(tr, end) - qr;
    EXPECT_NEAR(k * e + k3 * e * e * e, mgl * std::cos(qr + e), 1e-6 * mgl) << integ;
    EXPECT_LT(e, 0.9 * mgl / k) << integ;
  }
}

TEST(ArmFriction, ALugreJointSticksBelowCoulombAndSlipsAboveIt) {
  // A torque offset below Fc, taken up monotonically (bristles overdamped), bends the bristles to
  // z = offset / sigma0 and stops; on the way dz/dq = 1 - sigma0 z / Fc (Fs = Fc), so the joint rests at
  // q = -(Fc / sigma0) ln(1 - offset / Fc) (the offset opposes the drive: q < 0). Above Fc it slides,
  // and once the bristles are at Fc / sigma0 it accelerates at (offset - Fc) / J (b = 0).
  const double fc = 0.5, sigma0 = 1.0e4;
  for (const char* integ : kIntegrators) {
    for (const double offset : {0.4, 0.6}) {
      const ArmModel m = arm_from(rotor("{controller: {}, torque_offset: " + std::to_string(offset) +
                                            ", friction: {model: lugre, coulomb: 0.5, bristle_stiffness: 1.0e4, bristle_damping: 300}}",
                                        sim_with(integ, "duration: 1.0")));
      const ArmRun run = run_one(m);
      ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
      const ArmTrace& tr = run.traces[0];
      const std::vector<double>&q = tr.column("arm.q"), &w = tr.column("arm.qd");
      if (offset < fc) {
        const double rest = fc / sigma0 * std::log(1.0 - offset / fc);
        RecordProperty(std::string(integ) + "_stick_angle", fmt(q.back()));
        EXPECT_NEAR(q.back(), rest, 1e-4 * std::abs(rest)) << integ;
        EXPECT_LT(std::abs(w.back()), 1e-9) << integ;
        for (double x : w) EXPECT_LE(x, 1e-12) << integ;  // monotonic
      } else {
        const std::size_t half = q.size() / 2;
        const double accel = (w.back() - w[half]) / (tr.t().back() - tr.t()[half]);
        RecordProperty(std::string(integ) + "_slip_acceleration", fmt(accel));
        EXPECT_NEAR(accel, -(offset - fc) / kJ, 1e-6 * (offset - fc) / kJ) << integ;
      }
    }
  }
}

TEST(ArmFriction, ALugreJointTracksTheSameUnderCvodeAndTheFixedStepMethods) {
  // A PD move through stick, slip and presliding reversal: the fixed-step traces within their error
  // of CVODE's at rtol 1e-11.
  auto arm = [](const char* integ) {
    return arm_from(rotor("{controller: {kp: 20, kd: 2}, friction: {model: lugre, viscous: 0.05, coulomb: 0.5, stiction: 0.7, "
                          "stribeck_velocity: 0.05, bristle_stiffness: 1.0e4, bristle_damping: 20}}",
                          sim_with(integ, "duration: 2.0") +
                              "\ntrajectory:\n  waypoints:\n    - {time: 0.5, joints: {arm: 0.2}}\n    - {time: 1.0, joints: {arm: 0.0}}"));
  };
  const ArmRun ref = run_one(arm("cvode_dense"));
  ASSERT_EQ(ref.status[0], LaneStatus::kOk);
  const std::vector<double>& q_ref = ref.traces[0].column("arm.q");
  double travel = 0.0;
  for (double x : q_ref) travel = std::max(travel, std::abs(x));
  EXPECT_GT(travel, 0.1);
  for (const char* integ : {"rk4", "midpoint", "sdirk2", "cvode_klu"}) {
    const ArmRun run = run_one(arm(integ));
    ASSERT_EQ(run.status[0], LaneStatus::kOk) << integ;
    const std::vector<double>& q = run.traces[0].column("arm.q");
    double err = 0.0;
    for (std::size_t k = 0; k < q.size(); ++k) err = std::max(err, std::abs(q[k] - q_ref[k]));
    RecordProperty(std::string(integ) + "_angle_error", fmt(err));
    EXPECT_LT(err, 1e-4 * travel) << integ;
  }
}

TEST(ArmSimulate, ALugreJointAndANonlinearDriveGiveTheSameBitsAloneAndInAnyLane) {
  for (const char* integ : {"rk4", "sdirk2", "cvode_dense"}) {
    std::vector<ArmModel> lanes;
    for (const char* drive : {", backlash: 2.0e-3, efficiency: 0.8", ", cubic_stiffness: 1.0e8", ""}) {
      std::string text = nonlinear_drive_arm(drive, integ, 0.3);
      text.replace(text.find("    drive:"), 0, "    friction: {model: lugre, coulomb: 0.5, bristle_stiffness: 1.0e4}\n");
      lanes.push_back(arm_from(text));
    }
    expect_same_bits_alone_and_in_any_lane(lanes, integ);
  }
}

TEST(ArmYaml, ABadDriveLawOrFrictionModelIsNamedAtItsKey) {
  const std::string eta = arm_error(nonlinear_drive_arm(", efficiency: 1.2", "rk4", 1.0));
  EXPECT_NE(eta.find("joints.arm.drive.efficiency: must be in (0, 1]"), std::string::npos) << eta;
  const std::string play = arm_error(nonlinear_drive_arm(", backlash: -1.0e-3", "rk4", 1.0));
  EXPECT_NE(play.find("joints.arm.drive.backlash"), std::string::npos) << play;
  const std::string model = arm_error(rotor("{controller: {}, friction: {model: dahl, coulomb: 0.5}}", "{duration: 1}"));
  EXPECT_NE(model.find("arm.yaml:11: joints.arm.friction.model: unknown friction model 'dahl'"), std::string::npos) << model;
  const std::string no_fc = arm_error(rotor("{controller: {}, friction: {model: lugre}}", "{duration: 1}"));
  EXPECT_NE(no_fc.find("joints.arm.friction"), std::string::npos) << no_fc;
  const std::string sigma = arm_error(rotor("{controller: {}, friction: {model: lugre, coulomb: 0.5, bristle_stiffness: 0}}",
                                            "{duration: 1}"));
  EXPECT_NE(sigma.find("joints.arm.friction.bristle_stiffness"), std::string::npos) << sigma;
}

}  // namespace
}  // namespace ff
