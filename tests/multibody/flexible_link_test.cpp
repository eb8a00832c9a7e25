// multibody/flexible_link and the joint springs: the passive forces, the lumping's structure, the
// cantilever's deflection against Euler–Bernoulli in both bending planes, torsion and pure bending
// moments against their closed forms, the planar reference rig's clamped frequencies
// (docs/reference-rig.md), and energy conservation of a free 3-D flexible link under RK4.
#include "multibody/flexible_link.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "multibody/algorithms.hpp"
#include "multibody/limits.hpp"
#include "multibody/statics.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kPi = std::numbers::pi;

// The body that carries dof j.
int body_of_dof(const Tree& tree, int j) {
  for (int i = 0; i < tree.num_bodies(); ++i)
    if (tree.body(i).dof == j) return i;
  return -1;
}

TEST(PassiveForces, AreMinusStiffnessTimesStretchMinusDampingTimesRateOnATwoJointTree) {
  // A revolute hub (k = 40 N·m/rad, c = 1.5 N·m·s/rad, q0 = 0.2 rad), a fixed bracket, then a
  // prismatic slider (k = 300 N/m, c = 7 N·s/m, q0 = -0.05 m): tau = -k (q - q0) - c qd.
  TreeSpec s;
  BodySpec hub;
  hub.mass = 1.0;
  hub.inertia = test::box_inertia(1.0, 0.2, 0.2, 0.1);
  hub.stiffness = 40.0;
  hub.damping = 1.5;
  hub.spring_reference = 0.2;
  BodySpec bracket = hub;
  bracket.parent = 0;
  bracket.joint = JointType::kFixed;
  bracket.stiffness = 99.0;  // a fixed joint's spring is ignored
  BodySpec slider = hub;
  slider.parent = 1;
  slider.joint = JointType::kPrismatic;
  slider.axis = Vec3::UnitX();
  slider.stiffness = 300.0;
  slider.damping = 7.0;
  slider.spring_reference = -0.05;
  s.bodies = {hub, bracket, slider};
  const Tree tree = make_tree(s);
  ASSERT_EQ(tree.nv(), 2);
  const Eigen::Vector2d q(0.5, 0.1), qd(-2.0, 0.4);
  VectorXd tau = VectorXd::Constant(2, std::numeric_limits<double>::quiet_NaN());  // every entry written
  calc_passive_forces(tree, q, qd, tau);
  EXPECT_DOUBLE_EQ(tau[0], -40.0 * (0.5 - 0.2) - 1.5 * -2.0);  // -12 + 3 = -9 N·m
  EXPECT_DOUBLE_EQ(tau[1], -300.0 * (0.1 + 0.05) - 7.0 * 0.4);  // -45 - 2.8 = -47.8 N
  EXPECT_DOUBLE_EQ(calc_spring_energy(tree, q), 0.5 * 40.0 * 0.3 * 0.3 + 0.5 * 300.0 * 0.15 * 0.15);
  // At the references and at rest: no force, no energy.
  calc_passive_forces(tree, Eigen::Vector2d(0.2, -0.05), Eigen::Vector2d::Zero(), tau);
  EXPECT_EQ(tau, Eigen::Vector2d::Zero());
  EXPECT_EQ(calc_spring_energy(tree, Eigen::Vector2d(0.2, -0.05)), 0.0);
  VectorXd wrong(3);
  EXPECT_THROW(calc_passive_forces(tree, q, qd, wrong), std::invalid_argument);
  EXPECT_THROW((void)calc_spring_energy(tree, wrong), std::invalid_argument);
}

TEST(PassiveForces, AddedToTauMakeAHingedBodyADampedOscillator) {
  // One body on a hinge about z (gravity along the axis: no moment), I_zz = 0.3 kg·m² about the axis:
  // qdd = (tau - k (q - q0) - c qd) / I with the passive forces added by the caller.
  TreeSpec s;
  BodySpec b;
  b.mass = 2.0;
  b.inertia = Vec3(0.2, 0.25, 0.3).asDiagonal();
  b.stiffness = 50.0;
  b.damping = 0.8;
  b.spring_reference = -0.1;
  s.bodies = {b};
  const Tree tree = make_tree(s);
  TreeWorkspace ws(tree);
  const VectorXd q = VectorXd::Constant(1, 0.4), qd = VectorXd::Constant(1, 1.5);
  VectorXd tau(1), qdd(1);
  calc_passive_forces(tree, q, qd, tau);
  tau[0] += 2.0;  // an applied torque, N·m
  calc_forward_dynamics(tree, q, qd, tau, qdd, ws);
  EXPECT_NEAR(qdd[0], (2.0 - 50.0 * 0.5 - 0.8 * 1.5) / 0.3, 1e-12);
}

// An aluminium bar 30 mm (local y) x 50 mm (local z): I_y = w h³/12 > I_z = h w³/12.
FlexibleLinkSpec aluminium_bar(double length, int segments) {
  const double w = 0.03, h = 0.05;
  FlexibleLinkSpec link;
  link.name = "bar";
  link.length = length;
  link.segments = segments;
  link.section.youngs_modulus = 70e9;
  link.section.shear_modulus = 26e9;
  link.section.density = 2700.0;
  link.section.area = w * h;
  link.section.second_moment_y = w * h * h * h / 12.0;  // 3.125e-7 m⁴
  link.section.second_moment_z = h * w * w * w / 12.0;  // 1.125e-7 m⁴
  link.section.torsion_constant = 0.196 * h * w * w * w;  // rectangle b/t = 5/3 (Roark): 2.65e-7 m⁴
  return link;
}

TEST(FlexibleLink, LumpsIntoHalfFullHalfSegmentsWithThreeSpringsPerCell) {
  FlexibleLinkSpec link = aluminium_bar(1.2, 5);
  link.stiffness_factor = 0.9;
  link.damping_time = 2e-3;
  link.payload.mass = 0.7;
  link.payload.com_offset = {0.02, 0.0, -0.01};
  link.payload.inertia = Vec3(1e-3, 2e-3, 2.5e-3).asDiagonal();
  const std::vector<double> ls = flexible_link_segment_lengths(link);
  ASSERT_EQ(ls.size(), 5u);
  const double l = 1.2 / 4;
  EXPECT_DOUBLE_EQ(ls[0], l / 2);
  EXPECT_DOUBLE_EQ(ls[2], l);
  EXPECT_DOUBLE_EQ(ls[4], l / 2);
  EXPECT_EQ(flexible_link_tip_point(link), Vec3(l / 2, 0.0, 0.0));

  TreeSpec spec;
  BodySpec hub;
  hub.mass = 3.0;
  hub.inertia = test::box_inertia(3.0, 0.2, 0.2, 0.2);
  spec.bodies = {hub};
  const Mat3 R = rotz(0.3) * roty(-0.2);
  const Vec3 at{0.1, 0.0, 0.05};
  const int tip = append_flexible_link(spec, 0, at, R, link);
  EXPECT_EQ(tip, 1 + 1 + 4 * 3 - 1);  // hub, root segment, 4 cells of 3 bodies
  ASSERT_EQ(spec.bodies.size(), 14u);
  EXPECT_EQ(spec.bodies[1].joint, JointType::kFixed);
  EXPECT_EQ(spec.bodies[1].parent, 0);
  EXPECT_EQ(spec.bodies[tip].name, "bar.seg4");
  EXPECT_EQ(spec.bodies[2].name, "bar.cell1.z");
  const Tree tree = make_tree(spec);
  EXPECT_EQ(tree.nv(), 1 + 4 * 3);

  // The springs of flexible_link.hpp: k = kappa E I / l, k_x = kappa G J / l; c = beta k.
  const BeamSection& sec = link.section;
  const double kz = 0.9 * sec.youngs_modulus * sec.second_moment_z / l, ky = 0.9 * sec.youngs_modulus * sec.second_moment_y / l,
               kx = 0.9 * sec.shear_modulus * sec.torsion_constant / l;
  for (int cell = 0; cell < 4; ++cell) {
    const int first = 2 + 3 * cell;
    const Body& bz = tree.body(first);
    const Body& by = tree.body(first + 1);
    const Body& bx = tree.body(first + 2);
    EXPECT_EQ(bz.axis, Vec3::UnitZ());
    EXPECT_EQ(by.axis, Vec3::UnitY());
    EXPECT_EQ(bx.axis, Vec3::UnitX());
    EXPECT_DOUBLE_EQ(bz.stiffness, kz);
    EXPECT_DOUBLE_EQ(by.stiffness, ky);
    EXPECT_DOUBLE_EQ(bx.stiffness, kx);
    EXPECT_DOUBLE_EQ(bx.damping, 2e-3 * kx);
    EXPECT_EQ(bz.mass, 0.0);
    EXPECT_EQ(by.mass, 0.0);
    // The cell centre: the previous segment's far end; the three joints share it.
    EXPECT_DOUBLE_EQ(bz.X_tree.r.x(), ls[cell]);
    EXPECT_EQ(by.X_tree.r, Vec3::Zero());
  }
  // Segment masses rho A l_s, the payload on the last: the whole link's centre of mass at rest is
  // (rho A L L/2 + m_p (L + offset)) / (rho A L + m_p) along the link from its root.
  double mass = 0.0;
  Vec3 moment = Vec3::Zero();
  const VectorXd q0 = VectorXd::Zero(tree.nv());
  for (int i = 1; i < tree.num_bodies(); ++i) {
    mass += tree.body(i).mass;
    moment += tree.body(i).mass * calc_point_position(tree, q0, i, tree.body(i).com);
  }
  const double m_link = sec.density * sec.area * 1.2;
  EXPECT_NEAR(mass, m_link + 0.7, 1e-12);
  const Vec3 com_local = (m_link * Vec3(0.6, 0.0, 0.0) + 0.7 * Vec3(1.22, 0.0, -0.01)) / (m_link + 0.7);
  EXPECT_LT((moment / mass - (at + R * com_local)).norm(), 1e-14);
  // The middle segment's inertia about its centre: the slender prism of flexible_link.hpp.
  const Body& mid = tree.body(2 + 3 * 1 + 2);
  const double m = sec.density * sec.area * l;
  EXPECT_NEAR(mid.inertia_com(0, 0), sec.density * l * (sec.second_moment_y + sec.second_moment_z), 1e-15);
  EXPECT_NEAR(mid.inertia_com(1, 1), m * l * l / 12 + sec.density * sec.second_moment_y * l, 1e-15);
  EXPECT_NEAR(mid.inertia_com(2, 2), m * l * l / 12 + sec.density * sec.second_moment_z * l, 1e-15);
}

TEST(FlexibleLink, PlanarTorsionFreeAndShortLinksHaveTheirJointCounts) {
  auto count = [](const FlexibleLinkSpec& link) {
    TreeSpec spec;
    append_flexible_link(spec, -1, Vec3::Zero(), Mat3::Identity(), link);
    const Tree tree = make_tree(spec);
    return std::pair{tree.num_bodies(), tree.nv()};
  };
  FlexibleLinkSpec link = aluminium_bar(1.0, 7);
  EXPECT_EQ(count(link), std::pair(1 + 6 * 3, 18));
  link.torsion = false;
  EXPECT_EQ(count(link), std::pair(1 + 6 * 2, 12));
  link.planar = true;
  EXPECT_EQ(count(link), std::pair(7, 6));  // the rig's chain: one z-joint per cell
  link.segments = 1;                        // one rigid segment of length L
  EXPECT_EQ(count(link), std::pair(1, 0));
  EXPECT_EQ(flexible_link_tip_point(link), Vec3(1.0, 0.0, 0.0));
  link.segments = 2;  // two halves
  EXPECT_EQ(flexible_link_segment_lengths(link), (std::vector<double>{0.5, 0.5}));
  EXPECT_EQ(count(link), std::pair(2, 1));
}

TEST(FlexibleLink, BadSpecsAreRejectedNamingTheLink) {
  auto rejects = [](FlexibleLinkSpec link, int parent, const std::string& needle) {
    TreeSpec spec;
    try {
      append_flexible_link(spec, parent, Vec3::Zero(), Mat3::Identity(), link);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("flexible link \"bar\""), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      return;
    }
    ADD_FAILURE() << "accepted: " << needle;
  };
  const FlexibleLinkSpec good = aluminium_bar(1.0, 4);
  rejects(good, 0, "parent 0");
  FlexibleLinkSpec b = good;
  b.length = 0.0;
  rejects(b, -1, "length");
  b = good;
  b.segments = 0;
  rejects(b, -1, "segments 0 must be 1..256");
  b.segments = kMaxFlexibleSegments + 1;  // was built: a million segments reached 2 GB in 90 s
  rejects(b, -1, "segments 257 must be 1..256");
  b.segments = kMaxFlexibleSegments;
  TreeSpec longest;
  EXPECT_EQ(append_flexible_link(longest, -1, Vec3::Zero(), Mat3::Identity(), b), 3 * kMaxFlexibleSegments - 3);
  EXPECT_EQ(make_tree(longest).num_bodies(), 3 * kMaxFlexibleSegments - 2);
  b = good;
  b.section.second_moment_y = -1.0;
  rejects(b, -1, "I_y");
  b = good;
  b.section.shear_modulus = 0.0;
  rejects(b, -1, "shear modulus");
  b.torsion = false;  // without torsion G is not needed
  TreeSpec ok;
  EXPECT_NO_THROW(append_flexible_link(ok, -1, Vec3::Zero(), Mat3::Identity(), b));
  b = good;
  b.stiffness_factor = 0.0;
  rejects(b, -1, "stiffness factor");
  b = good;
  b.damping_time = -1e-3;
  rejects(b, -1, "damping time");
  b = good;
  b.payload.mass = -1.0;
  rejects(b, -1, "payload mass");
  b = good;
  b.payload.inertia(0, 1) = 1.0;
  rejects(b, -1, "not symmetric");
}

// The tip's displacement along the unit vector `down` when the link's own weight (gravity -z) and a
// tip load P act, from the static equilibrium: a cantilever on the fixed base, placed with `R`.
struct Cantilever {
  double deflection = 0.0;
  int iterations = 0, jacobians = 0;
};

Cantilever solve_cantilever(const FlexibleLinkSpec& link, const Mat3& R, double P, bool load_as_payload) {
  const double g = 9.81;
  FlexibleLinkSpec l = link;
  if (load_as_payload) l.payload.mass = P / g;  // a tip mass whose weight is P
  TreeSpec spec;
  const int tip = append_flexible_link(spec, -1, Vec3(0.2, -0.1, 1.0), R, l);
  const Tree tree = make_tree(spec);
  TreeWorkspace ws(tree);
  const VectorXd q0 = VectorXd::Zero(tree.nv());
  VectorXd tau = VectorXd::Zero(tree.nv());
  const Vec3 p = flexible_link_tip_point(l);
  if (!load_as_payload) add_point_load(tree, q0, tip, p, Vec3(0.0, 0.0, -P), Vec3::Zero(), tau, ws);
  const StaticEquilibriumResult res = solve_static_equilibrium(tree, q0, tau);
  EXPECT_TRUE(res.converged()) << res.message;
  const Vec3 d = calc_point_position(tree, res.q, tip, p) - calc_point_position(tree, q0, tip, p);
  return {-d.z(), res.iterations, res.jacobians};
}

TEST(FlexibleLinkStatics, CantileverTipDeflectionConvergesToEulerBernoulliInBothBendingPlanes) {
  // A 0.5 m aluminium bar clamped horizontally along +x, gravity -z, plus P = 5 N at the tip;
  // kappa = 1. Euler–Bernoulli: delta = q L⁴/(8 E I) + P L³/(3 E I), q = rho A g.
  // Plane y: the link's axes as the base's: the load bends it about local y (I_y), P by add_point_load.
  // Plane z: the link turned by rotx(90°) (local y up): it bends about local z (I_z), P as a tip payload.
  // The lumped chain (analysis): joint j at the cell centre x_j carries the exact moment of the load
  // beyond it, so delta_N = (l/EI) sum_j M(x_j)(L - x_j), the midpoint rule of the exact integral;
  // its error is exactly -(q L⁴/16 + P L³/12) / (E I (N-1)²) in linear theory, i.e. here
  // C/(N-1)² relative with C = -0.3996 in either plane (second order in the cell length). What
  // remains is the geometric nonlinearity, ~(delta/L)² < 2e-8 (delta/L <= 1.3e-4).
  const double L = 0.5, P = 5.0, g = 9.81;
  for (const bool plane_z : {false, true}) {
    const FlexibleLinkSpec base = aluminium_bar(L, 2);
    const BeamSection& s = base.section;
    const double EI = s.youngs_modulus * (plane_z ? s.second_moment_z : s.second_moment_y);
    const double q = s.density * s.area * g;
    const double exact = q * std::pow(L, 4) / (8 * EI) + P * std::pow(L, 3) / (3 * EI);
    const double lumping = -(q * std::pow(L, 4) / 16 + P * std::pow(L, 3) / 12) / EI / exact;  // times 1/(N-1)²
    EXPECT_NEAR(lumping, -0.3996, 1e-4);
    const Mat3 R = plane_z ? rotx(kPi / 2) : Mat3::Identity();
    double prev = 1.0, worst_nonlinear = 0.0;
    std::string table;
    std::printf("  plane %s: Euler-Bernoulli %.9e m, C = %.6f\n", plane_z ? "z" : "y", exact, lumping);
    for (const int N : {4, 8, 16, 32, 64}) {
      FlexibleLinkSpec link = base;
      link.segments = N;
      const Cantilever c = solve_cantilever(link, R, P, plane_z);
      const double err = c.deflection / exact - 1.0;
      const double n2 = (N - 1.0) * (N - 1.0);
      EXPECT_LT(std::abs(err), prev) << "N = " << N;  // falls with N
      const double lumped = exact * (1.0 + lumping / n2);  // the chain's linear closed form
      EXPECT_NEAR(c.deflection / lumped - 1.0, 0.0, 1e-7) << "N = " << N << ": the midpoint-rule error";
      worst_nonlinear = std::max(worst_nonlinear, std::abs(c.deflection / lumped - 1.0));
      std::printf("  plane %s N = %2d: tip %.9e m, error %+.4e (C/(N-1)^2 %+.4e), iterations %d\n",
                  plane_z ? "z" : "y", N, c.deflection, err, lumping / n2, c.iterations);
      EXPECT_LE(c.iterations, 3) << "N = " << N;
      EXPECT_EQ(c.jacobians, 1) << "N = " << N;  // the first Jacobian serves every step (chord steps)
      prev = std::abs(err);
      table += "N=" + std::to_string(N) + ":" + test::sci(c.deflection) + "m(" + test::sci(err) + ") ";
    }
    EXPECT_LT(prev, 2e-4);  // N = 64: 1.1e-4, well under 1 %
    EXPECT_LT(exact / L, 1e-3);  // small: the linear theory applies
    RecordProperty(plane_z ? "plane_z" : "plane_y", table);
    RecordProperty(plane_z ? "plane_z_nonlinear" : "plane_y_nonlinear", test::sci(worst_nonlinear));
  }
}

TEST(FlexibleLinkStatics, TipTorqueTwistsByTLOverGJAndTipMomentsBendByMLOverEI) {
  // A pure moment at the tip is carried unchanged by every cell, so the springs act in series:
  // twist T L/(G J) (the torsion springs: (N-1) l/(kappa G J) = L/(G J) for N >= 2), tip rotation
  // M L/(E I) in either bending plane and tip deflection M L²/(2 E I) (the midpoint rule is exact
  // for the linear moment arm). A turned placement, gravity off. The angles (1e-5 .. 2e-3 rad) are
  // read from R^T R_tip, good to ~1e-16 rad absolute; the deflections carry the chain's geometric
  // nonlinearity, ~angle²/6 < 1e-8 relative.
  const Mat3 R = rotz(0.4) * roty(-0.3);
  for (const int N : {1, 2, 3, 8, 33}) {
    const FlexibleLinkSpec link = aluminium_bar(0.8, N);
    const BeamSection& s = link.section;
    TreeSpec spec;
    spec.gravity.setZero();
    const int tip = append_flexible_link(spec, -1, Vec3(0.3, 0.2, 0.1), R, link);
    const Tree tree = make_tree(spec);
    TreeWorkspace ws(tree);
    const VectorXd q0 = VectorXd::Zero(tree.nv());
    const Vec3 p = flexible_link_tip_point(link);
    for (int axis = 0; axis < 3; ++axis) {
      const double torque = axis == 0 ? 20.0 : 2.0;  // N·m: twist ~1e-3 rad, bending ~1e-5 rad
      VectorXd tau = VectorXd::Zero(tree.nv());
      add_point_load(tree, q0, tip, p, Vec3::Zero(), R * (torque * Vec3::Unit(axis)), tau, ws);
      const StaticEquilibriumResult res = solve_static_equilibrium(tree, q0, tau);
      ASSERT_TRUE(res.converged()) << res.message;
      const Pose pose = calc_body_pose(tree, res.q, tip);
      const Mat3 Rrel = R.transpose() * pose.rotation;   // the tip's axes in the root's
      const Vec3 d = R.transpose() * (pose.point(p) - calc_point_position(tree, q0, tip, p));
      const double EIz = s.youngs_modulus * s.second_moment_z, EIy = s.youngs_modulus * s.second_moment_y;
      const double L = N > 1 ? 0.8 : 0.0;  // N = 1: rigid
      if (axis == 0) {
        const double twist = std::atan2(Rrel(2, 1), Rrel(1, 1));
        EXPECT_NEAR(twist, torque * L / (s.shear_modulus * s.torsion_constant), 1e-15) << "N = " << N;
        EXPECT_LT(d.norm(), 1e-15);  // twisting moves no point of the axis
      } else if (axis == 1) {  // about y: the tip turns z -> x' (rotation about +y) and goes down (-z)
        const double angle = std::atan2(Rrel(0, 2), Rrel(0, 0));
        EXPECT_NEAR(angle, torque * L / EIy, 1e-15) << "N = " << N;
        EXPECT_NEAR(-d.z(), torque * L * L / (2 * EIy), 1e-7 * torque * 0.64 / EIy) << "N = " << N;
      } else {  // about z: the tip goes sideways (+y)
        const double angle = std::atan2(Rrel(1, 0), Rrel(0, 0));
        EXPECT_NEAR(angle, torque * L / EIz, 1e-15) << "N = " << N;
        EXPECT_NEAR(d.y(), torque * L * L / (2 * EIz), 1e-7 * torque * 0.64 / EIz) << "N = " << N;
      }
    }
  }
}

// The planar reference rig of docs/reference-rig.md as a flexible link on the fixed base (the hub
// clamped): L = 4.1656 m, h = 0.3048 m, t = 0.01905 m, steel, bending in the horizontal plane about
// the vertical axis (local z, I_z = h t³/12), kappa = 39.5e3 (L/5)/(E I) so that k = 39.5 kN·m/rad at
// N = 6, the payload 328.7 kg with 118.6 kg·m² about its centre of mass at the tip point (the planar
// chain sees only I_zz; the tensor is taken isotropic so that the 3-D link below is valid).
FlexibleLinkSpec reference_rig(int N, bool planar) {
  const double L = 4.1656, h = 0.3048, t = 0.01905, E = 207e9;
  FlexibleLinkSpec link;
  link.name = "beam";
  link.length = L;
  link.segments = N;
  link.planar = planar;
  link.section.youngs_modulus = E;
  link.section.shear_modulus = 79.3e9;
  link.section.density = 7750.0;
  link.section.area = h * t;
  link.section.second_moment_z = h * t * t * t / 12.0;  // 1.7560e-7 m⁴: the horizontal bending
  link.section.second_moment_y = t * h * h * h / 12.0;  // the stiff vertical plane
  link.section.torsion_constant = h * t * t * t / 3.0 * (1.0 - 0.63 * t / h);  // thin strip
  link.stiffness_factor = 39.5e3 * (L / 5.0) / (E * link.section.second_moment_z);  // 0.905348
  link.payload.mass = 328.7;
  link.payload.inertia = 118.6 * Mat3::Identity();
  return link;
}

// Natural frequencies (Hz, ascending) of the undamped linearisation at q = 0: K v = omega² M v, K
// the joint springs (gravity off), M from the CRBA.
std::vector<double> clamped_frequencies(const FlexibleLinkSpec& link) {
  TreeSpec spec;
  spec.gravity.setZero();
  append_flexible_link(spec, -1, Vec3::Zero(), Mat3::Identity(), link);
  const Tree tree = make_tree(spec);
  TreeWorkspace ws(tree);
  const int n = tree.nv();
  MatrixXd M(n, n), K(n, n);
  const VectorXd q0 = VectorXd::Zero(n);
  calc_mass_matrix(tree, q0, M, ws);
  calc_static_stiffness(tree, q0, K, ws);
  const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixXd> eig(K, M, Eigen::EigenvaluesOnly);
  std::vector<double> f;
  for (int i = 0; i < n; ++i) f.push_back(std::sqrt(eig.eigenvalues()[i]) / (2 * kPi));
  return f;
}

TEST(FlexibleLinkModes, PlanarReferenceRigHasTheClampedFrequenciesOfTheReferencePage) {
  // docs/reference-rig.md: N = 6: 0.300 Hz and 2.300 Hz; N = 48: 0.2985 Hz and 2.275 Hz. The lumping
  // is the rig's own (segment inertia about the vertical axis m (l_s² + t²)/12 = I_zz of the prism),
  // so these agree to the digits given (measured 0.300001, 2.300267; 0.298498, 2.274907 Hz).
  const FlexibleLinkSpec rig6 = reference_rig(6, true);
  {
    TreeSpec spec;
    append_flexible_link(spec, -1, Vec3::Zero(), Mat3::Identity(), rig6);
    EXPECT_NEAR(make_tree(spec).body(1).stiffness, 39.5e3, 1e-9);
  }
  const std::vector<double> f6 = clamped_frequencies(rig6);
  ASSERT_EQ(f6.size(), 5u);
  EXPECT_NEAR(f6[0], 0.300, 0.0005);
  EXPECT_NEAR(f6[1], 2.300, 0.0005);
  const std::vector<double> f48 = clamped_frequencies(reference_rig(48, true));
  EXPECT_NEAR(f48[0], 0.2985, 0.00005);
  EXPECT_NEAR(f48[1], 2.275, 0.0005);
  std::printf("  N = 6: %.6f Hz, %.6f Hz; N = 48: %.6f Hz, %.6f Hz\n", f6[0], f6[1], f48[0], f48[1]);
  RecordProperty("N6_hz", test::sci(f6[0]) + " " + test::sci(f6[1]));
  RecordProperty("N48_hz", test::sci(f48[0]) + " " + test::sci(f48[1]));
  // The 3-D link (three springs per cell) holds the planar modes unchanged: at q = 0 the horizontal
  // bending decouples from the vertical bending and the torsion (the section and payload are symmetric).
  const std::vector<double> f3d = clamped_frequencies(reference_rig(6, false));
  ASSERT_EQ(f3d.size(), 15u);
  for (const double f : {f6[0], f6[1], f6[4]}) {
    const double nearest = *std::min_element(f3d.begin(), f3d.end(), [f](double a, double b) {
      return std::abs(a - f) < std::abs(b - f);
    });
    EXPECT_NEAR(nearest, f, 1e-9 * f);
  }
}

TEST(FlexibleLinkDynamics, FreeLinkOnARevoluteHubConservesEnergyUnderRk4) {
  // A soft polymer bar (E = 30 MPa, G = 10 MPa, 1200 kg/m³, 20 x 40 mm, L = 0.5 m, N = 3: two elastic
  // spherical joints, 6 springs) on a hub spinning freely about the vertical z axis, tilted 0.1 rad off
  // the horizontal, with an off-axis tip payload; gravity -z (its own weight alone sags it ~5 % of L),
  // no damping. Released bent in both planes (0.15 rad cell angles, untwisted) with the hub at
  // 2 rad/s; the torsion is excited by the 3-D coupling. Modes at the start 19 .. 166 rad/s (bending)
  // and 437 rad/s (torsion). RK4 with h = 0.1 ms (h omega_max = 0.044), 0.3 s = 3000 steps: kinetic +
  // gravitational + spring energy stays within 1e-8 of the largest kinetic energy (measured 1.1e-9;
  // RK4's error, falling as h^4: 2.1e-10 at h = 70 us). ~20 ms in Release, ~1 s in the sanitizer
  // build (its test code at -O0).
  TreeSpec spec;
  BodySpec hub;
  hub.mass = 1.5;
  hub.com = {0.02, 0.0, 0.0};
  hub.inertia = Vec3(0.004, 0.004, 0.006).asDiagonal();
  spec.bodies = {hub};
  const double w = 0.02, h = 0.04;
  FlexibleLinkSpec link;
  link.length = 0.5;
  link.segments = 3;
  link.section = {3e7, 1e7, 1200.0, w * h, w * h * h * h / 12, h * w * w * w / 12, 0.229 * h * w * w * w};
  link.payload.mass = 0.1;
  link.payload.com_offset = {0.01, 0.005, -0.01};
  link.payload.inertia = Vec3(2e-5, 3e-5, 4e-5).asDiagonal();
  append_flexible_link(spec, 0, Vec3(0.05, 0.0, 0.0), roty(-0.1), link);
  const Tree tree = make_tree(spec);
  const int n = tree.nv();
  ASSERT_EQ(n, 7);
  VectorXd x = VectorXd::Zero(2 * n);
  std::vector<int> twist_dofs;
  for (int j = 1; j < n; ++j) {
    const bool twist = tree.body(body_of_dof(tree, j)).axis.x() > 0.5;
    if (twist) twist_dofs.push_back(j);
    x[j] = twist ? 0.0 : 0.15 * std::sin(1.3 * j + 0.4);
  }
  x[n] = 2.0;  // hub rate, rad/s
  test::Rk4 rk(tree);
  auto energy = [&](const VectorXd& y) {
    return calc_kinetic_energy(tree, y.head(n), y.tail(n), rk.ws) + calc_potential_energy(tree, y.head(n), rk.ws) +
           calc_spring_energy(tree, y.head(n));
  };
  const double E0 = energy(x), V_spring0 = calc_spring_energy(tree, x.head(n));
  double drift = 0.0, T_max = 0.0, twist_max = 0.0;
  for (int step = 1; step <= 3000; ++step) {
    rk.step(x, 1e-4);
    if (step % 5 == 0) {  // every 0.5 ms
      drift = std::max(drift, std::abs(energy(x) - E0));
      T_max = std::max(T_max, calc_kinetic_energy(tree, x.head(n), x.tail(n), rk.ws));
      for (const int j : twist_dofs) twist_max = std::max(twist_max, std::abs(x[j]));
    }
  }
  ASSERT_TRUE(x.allFinite());
  EXPECT_GT(V_spring0, 0.08);   // J: the bent state's springs
  EXPECT_GT(T_max, 0.2);        // J: the motion's kinetic energy (hub and bar)
  EXPECT_GT(twist_max, 1e-3);   // rad: the torsion joints take part
  EXPECT_GT(x[0], 0.5);         // rad: the hub has turned
  EXPECT_LT(drift / T_max, 1e-8) << "drift " << drift << " J of " << T_max << " J";
  std::printf("  drift %.3e J of T_max %.4f J (relative %.3e), spring energy at release %.4f J, max twist %.3e rad\n",
              drift, T_max, drift / T_max, V_spring0, twist_max);
  RecordProperty("relative_energy_drift", test::sci(drift / T_max));
  RecordProperty("twist_max_rad", test::sci(twist_max));
}

TEST(FlexibleLinkRootJoint, DefaultsToFixedAndNamesTheRootSegmentSeg0UnlessRootNameIsGiven) {
  TreeSpec spec;
  append_flexible_link(spec, -1, Vec3::Zero(), Mat3::Identity(), aluminium_bar(1.0, 3));
  EXPECT_EQ(spec.bodies.at(0).name, "bar.seg0");
  EXPECT_EQ(spec.bodies.at(0).joint, JointType::kFixed);
  FlexibleLinkSpec named = aluminium_bar(1.0, 3);
  named.root_name = "forearm";
  TreeSpec other;
  append_flexible_link(other, -1, Vec3::Zero(), Mat3::Identity(), named);
  EXPECT_EQ(other.bodies.at(0).name, "forearm");
  EXPECT_EQ(other.bodies.at(1).name, "bar.cell1.z");
}

TEST(FlexibleLinkRootJoint, MovesTheRootSegmentAsAMasslessHubWithThatJointWould) {
  // A revolute root joint (axis y, armature 0.3 kg·m², k = 50 N·m/rad, c = 2 N·m·s/rad, q0 = 0.1 rad)
  // against the same joint on a massless hub body with the link fixed to it: the same M(q), bias and
  // passive forces at a random state, one body fewer.
  const Vec3 at(0.1, -0.2, 0.3);
  const Mat3 R = rotz(0.4) * rotx(-0.3);
  FlexibleLinkSpec link = aluminium_bar(0.8, 5);
  TreeSpec with_hub;
  BodySpec hub;
  hub.name = "hub";
  hub.axis = Vec3::UnitY();
  hub.position = at;
  hub.rotation = R;
  hub.armature = 0.3;
  hub.stiffness = 50.0;
  hub.damping = 2.0;
  hub.spring_reference = 0.1;
  with_hub.bodies.push_back(hub);
  append_flexible_link(with_hub, 0, Vec3::Zero(), Mat3::Identity(), link);
  link.root_joint = {.type = JointType::kRevolute, .axis = Vec3::UnitY(), .armature = 0.3, .stiffness = 50.0,
                     .damping = 2.0, .spring_reference = 0.1};
  TreeSpec direct;
  const int tip = append_flexible_link(direct, -1, at, R, link);
  const Tree a = make_tree(with_hub), b = make_tree(direct);
  ASSERT_EQ(b.num_bodies() + 1, a.num_bodies());
  ASSERT_EQ(a.nv(), b.nv());
  EXPECT_EQ(tip, b.num_bodies() - 1);
  EXPECT_EQ(b.body(0).dof, 0);
  const VectorXd q = VectorXd::Random(a.nv()), qd = VectorXd::Random(a.nv());
  TreeWorkspace wa(a), wb(b);
  MatrixXd Ma(a.nv(), a.nv()), Mb(b.nv(), b.nv());
  calc_mass_matrix(a, q, Ma, wa);
  calc_mass_matrix(b, q, Mb, wb);
  EXPECT_LE((Ma - Mb).cwiseAbs().maxCoeff(), 1e-12 * Ma.cwiseAbs().maxCoeff());
  VectorXd ha(a.nv()), hb(b.nv()), pa(a.nv()), pb(b.nv());
  calc_bias_forces(a, q, qd, ha, wa);
  calc_bias_forces(b, q, qd, hb, wb);
  EXPECT_LE((ha - hb).cwiseAbs().maxCoeff(), 1e-10 * ha.cwiseAbs().maxCoeff());
  calc_passive_forces(a, q, qd, pa);
  calc_passive_forces(b, q, qd, pb);
  EXPECT_LE((pa - pb).cwiseAbs().maxCoeff(), 1e-12 * pa.cwiseAbs().maxCoeff());
  EXPECT_NEAR(pb[0], -50.0 * (q[0] - 0.1) - 2.0 * qd[0], 1e-12);
}

}  // namespace
}  // namespace ff
