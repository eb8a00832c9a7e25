// The seed's 100-DOF flexible arm (configs/flex100.yaml: two arms, each a 2 m tube lumped into 33
// segments in 3-D) against the continuous beam it lumps: with every drive locked each arm is a
// cantilever carrying its gripper, whose natural frequencies follow, independently of the lumping,
// from the Euler-Bernoulli tip-body frequency equation (tests/multibody/euler_bernoulli_frame.hpp,
// bending in each plane) and the uniform shaft with a tip disc (torsion). The first three of those
// must be the lumped arm's first three, within 1 %. Gravity and the links' dampers are switched off:
// the beam's own frequencies, not the sag's geometric stiffness or the damped poles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/modes.hpp"
#include "tests/multibody/euler_bernoulli_frame.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

struct BeamMode {
  double omega;      // rad/s
  std::string kind;  // for the messages
};

// The continuous link's first three modes in each family, rad/s (clamped at the root, the payload a
// rigid body at the tip with its centre of mass on the tip point).
std::vector<BeamMode> continuous_modes(const FlexibleLinkSpec& link) {
  const BeamSection& s = link.section;
  const double L = link.length, rho_a = s.density * s.area;
  const double m = link.payload.mass;
  std::vector<BeamMode> out;
  // Bending about y (deflection along z) and about z (along y): beta_n L roots of the tip-body
  // equation with mu = m / (rho A L), j = J_tip / (rho A L^3); omega = (beta L)^2 sqrt(E I / (rho A L^4)).
  for (const int axis : {1, 2}) {
    const double EI = s.youngs_modulus * (axis == 1 ? s.second_moment_y : s.second_moment_z);
    const double mu = m / (rho_a * L), j = link.payload.inertia(axis, axis) / (rho_a * L * L * L);
    for (const double lambda : test::cantilever_tip_body_roots(mu, j, 3))
      out.push_back({lambda * lambda * std::sqrt(EI / (rho_a * std::pow(L, 4))), axis == 1 ? "bending y" : "bending z"});
  }
  // Torsion: a shaft of polar mass moment rho I_p per length (I_p = I_y + I_z, as the lumped segments
  // carry) and stiffness G J, a disc J_t at the free end: beta tan beta = rho I_p L / J_t with
  // beta = omega L / c, c = sqrt(G J / (rho I_p)) (J_t = 0: beta = (2n - 1) pi / 2).
  const double Ip = s.second_moment_y + s.second_moment_z, Jt = link.payload.inertia(0, 0);
  const double c = std::sqrt(s.shear_modulus * s.torsion_constant / (s.density * Ip));
  const double ratio = s.density * Ip * L / Jt;
  for (int n = 0; n < 3; ++n) {  // one root in each branch (n pi, n pi + pi/2) of tan
    const auto f = [&](double b) { return b * std::sin(b) - ratio * std::cos(b); };
    const auto roots = test::scan_roots(f, n * std::numbers::pi + 1e-9, n * std::numbers::pi + 0.5 * std::numbers::pi, 1e-4, 1);
    out.push_back({roots[0] * c / L, "torsion"});
  }
  std::sort(out.begin(), out.end(), [](const BeamMode& a, const BeamMode& b) { return a.omega < b.omega; });
  return out;
}

// configs/flex100.yaml with gravity and the dampers off and its six drives locked: the spec and the
// lumped arms' modes.
struct LockedArms {
  ArmSpec spec;
  std::vector<TreeMode> lumped;
};
LockedArms lock_flex100() {
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/flex100.yaml";
  YAML::Node doc = load_yaml_file(path);
  doc["gravity"] = std::vector<double>{0.0, 0.0, 0.0};
  for (YAML::Node b : doc["bodies"])
    if (b["flexible"]) b["flexible"]["damping_time"] = 0.0;
  LockedArms out{parse_arm_spec(doc, path), {}};
  const Tree tree = make_tree(out.spec.tree.spec);
  EXPECT_EQ(out.spec.tree.flexible_links.size(), 2u);
  EXPECT_EQ(tree.nv(), 198);  // two arms of 3 drives + 32 cells x 3 elastic joints
  TreeModeOptions options;
  for (const JointControlSpec& j : out.spec.joints) options.locked_dofs.push_back(out.spec.tree.dof_index.at(j.joint));
  EXPECT_EQ(options.locked_dofs.size(), 6u);
  out.lumped = calc_tree_modes(tree, Eigen::VectorXd::Zero(tree.nv()), options);
  return out;
}

TEST(LongFlexibleArm, LockedArmsFirstThreeModesAreTheContinuousBeamsWithinOnePercent) {
  const auto [spec, lumped] = lock_flex100();
  ASSERT_EQ(spec.tree.flexible_links.size(), 2u);

  // Both arms are the same link: each continuous frequency is two of the lumped arm's (one per arm).
  const FlexibleLinkSpec& link = spec.tree.flexible_links[0].link;
  EXPECT_EQ(link.segments, 33);
  const std::vector<BeamMode> beam = continuous_modes(link);
  for (int n = 0; n < 3; ++n) {
    RecordProperty("mode" + std::to_string(n + 1) + "_continuous_rad_s", test::sci(beam[static_cast<std::size_t>(n)].omega));
    for (int arm = 0; arm < 2; ++arm) {
      const double w = lumped[static_cast<std::size_t>(2 * n + arm)].omega_n;
      const double err = w / beam[static_cast<std::size_t>(n)].omega - 1.0;
      RecordProperty("mode" + std::to_string(n + 1) + "_arm" + std::to_string(arm) + "_rad_s", test::sci(w));
      RecordProperty("mode" + std::to_string(n + 1) + "_arm" + std::to_string(arm) + "_error", test::sci(err));
      EXPECT_LT(std::abs(err), 0.01) << "mode " << n + 1 << " (" << beam[static_cast<std::size_t>(n)].kind
                                     << ", " << beam[static_cast<std::size_t>(n)].omega << " rad/s), lumped " << w;
    }
  }
  // The seventh is above the third pair (no mode of the continuous beam is missed in between).
  EXPECT_GT(lumped[6].omega_n, 1.01 * beam[2].omega);
}

TEST(LongFlexibleArm, TheFirstTorsionModeIs951RadPerSecondByTheShaftEquationAndLumped) {
  // docs/flex100.md: beta tan beta = rho I_p L / J_t gives 951.1 rad/s; the lumped arm (N = 33) 951.09.
  const auto [spec, lumped] = lock_flex100();
  double torsion = 0.0;
  for (const BeamMode& m : continuous_modes(spec.tree.flexible_links.at(0).link))
    if (m.kind == "torsion" && torsion == 0.0) torsion = m.omega;
  EXPECT_NEAR(torsion, 951.13, 0.01);
  ASSERT_GE(lumped.size(), 10u);
  EXPECT_NEAR(lumped[8].omega_n, 951.09, 0.01);  // the fifth pair: after bending z, y, z and y
  EXPECT_NEAR(lumped[9].omega_n, 951.09, 0.01);
}

}  // namespace
}  // namespace ff
