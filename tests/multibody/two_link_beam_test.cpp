// The lumped two-link flexible arm (two multibody/flexible_link.hpp links, both arm joints locked)
// against the continuous one: the natural frequencies of two Euler–Bernoulli beams rigidly joined at
// an elbow angle, from the exact frequency determinant of tests/multibody/euler_bernoulli_frame.hpp.
// First the oracle itself against closed forms (a straight arm of equal links is one cantilever; a
// tip mass gives the cantilever-with-tip-mass frequency equation and Blevins's tabulated value; a
// rigid second link at a right angle is a tip body on link 1), then the lumped arm's first three
// modes converging to the oracle's as the links are cut finer, straight, at a right angle and at
// 45 deg, bare and with a payload.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "multibody/flexible_link.hpp"
#include "multibody/modes.hpp"
#include "tests/multibody/euler_bernoulli_frame.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using test::EbLink;
using test::EbTwoLinkArm;

// beta_n L of the clamped-free beam (1 + cos cosh = 0).
constexpr double kCantileverBetaL[3] = {1.875104068711961, 4.694091132974175, 7.854757438237613};

// A link's beta_n L from omega_n (rad/s) over its length.
double beta_l(const EbLink& link, double omega) { return test::eb_beta(link, omega) * link.length; }

TEST(TwoLinkBeamOracle, StraightArmOfEqualLinksIsOneCantilever) {
  // phi = 0, equal sections: the elbow conditions are those of a section inside one beam, so the arm
  // is a cantilever of length L1 + L2.
  for (const double L2 : {0.6, 0.2, 1.5}) {
    EbTwoLinkArm arm;
    arm.link1 = {0.7, 6.3, 0.324};
    arm.link2 = {L2, 6.3, 0.324};
    const std::vector<double> omega = test::two_link_natural_frequencies(arm, 3);
    const EbLink whole{0.7 + L2, 6.3, 0.324};
    for (int k = 0; k < 3; ++k) {
      const double lambda = beta_l(whole, omega[static_cast<std::size_t>(k)]);
      const double err = std::abs(lambda / kCantileverBetaL[k] - 1.0);
      RecordProperty("L2_" + std::to_string(L2).substr(0, 3) + "_mode" + std::to_string(k + 1),
                     test::sci(err));
      EXPECT_LT(err, 1e-10) << "L2 " << L2 << " mode " << k + 1;
    }
  }
}

TEST(TwoLinkBeamOracle, TipMassGivesTheCantileverTipMassFrequencyEquationAndBlevinsValue) {
  // The frequency equation of a cantilever with a tip mass, solved on its own (mu = m_p / (rho A L)):
  // 1 + cos cosh + mu beta L (cos sinh - sin cosh) = 0. Without the mass it is 1 + cos cosh = 0;
  // Blevins (Formulas for Natural Frequency and Mode Shape, 1979, ch. 8) tabulates beta_1 L = 1.2479
  // at mu = 1. The straight arm of equal links carrying m_p is that cantilever.
  const std::vector<double> bare = test::cantilever_tip_body_roots(0.0, 0.0, 3);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(bare[static_cast<std::size_t>(k)], kCantileverBetaL[k], 1e-12);
  EXPECT_NEAR(test::cantilever_tip_body_roots(1.0, 0.0, 1)[0], 1.2479, 5e-5);
  for (const double mu : {0.2, 1.0, 5.0}) {
    const std::vector<double> closed = test::cantilever_tip_body_roots(mu, 0.0, 3);
    EbTwoLinkArm arm;
    arm.link1 = {0.7, 6.3, 0.324};
    arm.link2 = {0.6, 6.3, 0.324};
    arm.tip_mass = mu * 0.324 * 1.3;
    const std::vector<double> omega = test::two_link_natural_frequencies(arm, 3);
    const EbLink whole{1.3, 6.3, 0.324};
    for (int k = 0; k < 3; ++k) {
      const double err = std::abs(beta_l(whole, omega[static_cast<std::size_t>(k)]) /
                                  closed[static_cast<std::size_t>(k)] - 1.0);
      RecordProperty("mu_" + std::to_string(mu).substr(0, 3) + "_mode" + std::to_string(k + 1), test::sci(err));
      EXPECT_LT(err, 1e-10) << "mu " << mu << " mode " << k + 1;
    }
  }
}

TEST(TwoLinkBeamOracle, RigidSecondLinkAtARightAngleIsATipBodyOnLinkOne) {
  // phi = 90 deg, link 2 made 1e8 times stiffer than link 1: a rigid body fixed to link 1's tip. Its
  // centre of mass lies on link 1's transverse line through the elbow, so its translation along y
  // (link 2 sliding along its axis: the whole mass M = rho A2 L2 + m_p) and its rotation about the
  // elbow (J = rho A2 L2^3 / 3 + m_p L2^2 + J_p) do not couple: link 1 is a cantilever with tip mass
  // M and rotary inertia J, whose frequency equation (the clamped-free determinant with the tip
  // body's conditions, expanded) is
  // 1 + cos cosh + l mu (cos sinh - sin cosh) - l^3 j (sin cosh + cos sinh) + l^4 mu j (1 - cos cosh)
  // = 0, mu = M / (rho A1 L1), j = J / (rho A1 L1^3). The remaining flexibility of link 2 moves the
  // frequencies by ~3e-9 relative.
  EbTwoLinkArm arm;
  arm.link1 = {0.7, 6.3, 0.324};
  arm.link2 = {0.6, 6.3e8, 0.162};
  arm.elbow_angle = std::numbers::pi / 2.0;
  arm.tip_mass = 0.2;
  arm.tip_inertia = 1e-3;
  const double M = 0.162 * 0.6 + 0.2, J = 0.162 * std::pow(0.6, 3) / 3.0 + 0.2 * 0.36 + 1e-3;
  const std::vector<double> closed =
      test::cantilever_tip_body_roots(M / (0.324 * 0.7), J / (0.324 * std::pow(0.7, 3)), 3);
  const std::vector<double> omega = test::two_link_natural_frequencies(arm, 3);
  for (int k = 0; k < 3; ++k) {
    const double err = std::abs(beta_l(arm.link1, omega[static_cast<std::size_t>(k)]) /
                                closed[static_cast<std::size_t>(k)] - 1.0);
    RecordProperty("mode" + std::to_string(k + 1), test::sci(err));
    EXPECT_LT(err, 1e-6) << "mode " << k + 1;
  }
}

// The arm of the lumped-vs-continuous tests: two aluminium strips (E = 70 GPa, rho = 2700 kg/m³)
// bending in their soft plane, the horizontal plane of a planar arm, as in the classic two-link
// flexible arm benchmarks (links of 0.5-1 m, first modes of a few Hz): link 1 0.7 m of 40 x 3 mm
// (EI = 6.3 N·m², rho A = 0.324 kg/m), link 2 0.6 m of 30 x 2 mm (EI = 1.4 N·m², rho A = 0.162
// kg/m); the payload, when there is one, a 40 mm cube of 0.2 kg at link 2's tip
// (J_p = m a^2 / 6 = 5.3e-5 kg·m²). t / L <= 4.3e-3, so the lumped segments' rotary inertia
// rho I l, which the Euler–Bernoulli beam lacks, is (t/L)^2 / 12 ~ 1e-6 of the links': negligible.
struct Strip {
  double length, width, thickness;
};
constexpr double kE = 70e9, kG = 26e9, kRho = 2700.0;
constexpr Strip kLink1{0.7, 0.040, 0.003}, kLink2{0.6, 0.030, 0.002};
constexpr double kPayloadMass = 0.2, kPayloadSide = 0.04;

FlexibleLinkSpec lumped(const char* name, const Strip& s, int N) {
  FlexibleLinkSpec link;
  link.name = name;
  link.length = s.length;
  const double A = s.width * s.thickness, I = s.width * s.thickness * s.thickness * s.thickness / 12.0;
  link.section = {kE, kG, kRho, A, I, I, I};
  link.segments = N;
  link.planar = true;
  link.stiffness_factor = 1.0;
  return link;
}

EbLink continuous(const Strip& s) {
  return {s.length, kE * s.width * std::pow(s.thickness, 3) / 12.0, kRho * s.width * s.thickness};
}

// The lumped arm's first three modes against the continuous arm's for N = 6, 12, 24, 48 segments per
// link, kappa = 1 (k = E I / l: every spring scales together, so any other constant kappa multiplies
// every lumped frequency by sqrt(kappa) at every N, a bias no refinement removes; the rig's 0.905
// leaves -4.9 %). Measured (phi = 0, 45, 90 deg, bare or with the payload): the lumped frequencies lie
// above the continuous ones and the error falls as 1/N^2 (x 4.2-4.9 per doubling), from 0.25-1.7 %
// at N = 6 to 2.8e-5 .. 1.8e-4 at N = 48 (0.018 % at most). Checked: it falls by more than 3 at
// each doubling, and at N = 48 it is below 5e-4 for each of the three.
void expect_lumped_arm_converges(double phi, bool payload, const char* what) {
  EbTwoLinkArm arm;
  arm.link1 = continuous(kLink1);
  arm.link2 = continuous(kLink2);
  arm.elbow_angle = phi;
  const Mat3 payload_inertia = test::box_inertia(kPayloadMass, kPayloadSide, kPayloadSide, kPayloadSide);
  if (payload) {
    arm.tip_mass = kPayloadMass;
    arm.tip_inertia = payload_inertia(2, 2);
  }
  const std::vector<double> exact = test::two_link_natural_frequencies(arm, 3);
  for (int k = 0; k < 3; ++k)
    testing::Test::RecordProperty(std::string(what) + "_exact_hz_mode" + std::to_string(k + 1),
                                  test::sci(exact[static_cast<std::size_t>(k)] / (2.0 * std::numbers::pi)));
  double previous[3] = {1.0, 1.0, 1.0};
  for (int N : {6, 12, 24, 48}) {
    TreeSpec s;
    FlexibleLinkSpec link1 = lumped("link1", kLink1, N), link2 = lumped("link2", kLink2, N);
    if (payload) {
      link2.payload.mass = kPayloadMass;
      link2.payload.inertia = payload_inertia;
    }
    // Link 2's root segment fixed to link 1's tip segment at its tip point, turned by the elbow
    // angle about z: both arm joints locked, the cells' springs the only dofs.
    const int tip1 = append_flexible_link(s, -1, Vec3::Zero(), Mat3::Identity(), link1);
    append_flexible_link(s, tip1, flexible_link_tip_point(link1), rotz(phi), link2);
    s.gravity = Vec3::Zero();
    const Tree tree = make_tree(s);
    ASSERT_EQ(tree.nv(), 2 * (N - 1));
    const std::vector<TreeMode> modes = calc_tree_modes(tree, Eigen::VectorXd::Zero(tree.nv()));
    ASSERT_GE(modes.size(), 3u);
    for (int k = 0; k < 3; ++k) {
      const std::size_t kk = static_cast<std::size_t>(k);
      EXPECT_TRUE(modes[kk].oscillatory);
      const double err = std::abs(modes[kk].omega_n / exact[kk] - 1.0);
      testing::Test::RecordProperty(
          std::string(what) + "_N" + std::to_string(N) + "_mode" + std::to_string(k + 1), test::sci(err));
      EXPECT_LT(err, previous[k] / 3.0) << what << " N " << N << " mode " << k + 1;
      previous[k] = err;
    }
  }
  for (int k = 0; k < 3; ++k) EXPECT_LT(previous[k], 5e-4) << what << " mode " << k + 1 << " at N = 48";
}

TEST(TwoLinkBeam, LumpedArmConvergesToTheContinuousArmStraight) {
  expect_lumped_arm_converges(0.0, false, "phi0");
}

TEST(TwoLinkBeam, LumpedArmConvergesToTheContinuousArmStraightWithPayload) {
  expect_lumped_arm_converges(0.0, true, "phi0_payload");
}

TEST(TwoLinkBeam, LumpedArmConvergesToTheContinuousArmAtARightAngle) {
  expect_lumped_arm_converges(std::numbers::pi / 2.0, false, "phi90");
}

TEST(TwoLinkBeam, LumpedArmConvergesToTheContinuousArmAtARightAngleWithPayload) {
  expect_lumped_arm_converges(std::numbers::pi / 2.0, true, "phi90_payload");
}

TEST(TwoLinkBeam, LumpedArmConvergesToTheContinuousArmAt45DegreesWithPayload) {
  // Both elbow couplings at once: link 2's root deflects by cos phi and slides by sin phi of the
  // elbow's deflection.
  expect_lumped_arm_converges(std::numbers::pi / 4.0, true, "phi45_payload");
}

}  // namespace
}  // namespace ff
