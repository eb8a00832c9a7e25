// multibody/lanes: the lane-batched ABA against the scalar one (multibody/algorithms, itself checked
// against a dense CRBA/RNEA solve) on random trees whose lanes share a topology and nothing else, the
// same bits for a variant in any lane at any width, and the passive forces.
#include "multibody/lanes.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "multibody/algorithms.hpp"
#include "kernel/drive.hpp"
#include "kernel/friction.hpp"
#include "multibody/flexible_link.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

using Eigen::VectorXd;

// W random trees of one random topology (n bodies): parents and joint types drawn once, then
// every lane its own axes, placements, inertias, armature, springs and gravity.
// coordinate_axes: each body's axis one of ±x, ±y, ±z (drawn per lane) or, one body in five, a random
// one, and its rotation the identity half the time (the lane ABA's exact joint frames).
std::vector<Tree> random_lanes(test::Rng& rng, int n, int W, bool coordinate_axes = false) {
  std::vector<int> parent;
  std::vector<JointType> joint;
  for (int i = 0; i < n; ++i) {
    parent.push_back(rng.index(i + 1) - 1);
    const double u = rng.uniform();
    joint.push_back(u < 0.55 ? JointType::kRevolute : u < 0.8 ? JointType::kPrismatic : JointType::kFixed);
  }
  joint.back() = JointType::kRevolute;
  std::vector<Tree> trees;
  for (int l = 0; l < W; ++l) {
    TreeSpec s;
    for (int i = 0; i < n; ++i) {
      BodySpec b = test::random_body(rng, parent[static_cast<std::size_t>(i)], &joint[static_cast<std::size_t>(i)]);
      if (coordinate_axes && rng.uniform() < 0.8) {
        b.axis = Vec3::Unit(rng.index(3)) * (rng.uniform() < 0.5 ? -1.0 : 1.0);
        if (rng.uniform() < 0.5) b.rotation = Mat3::Identity();
      }
      b.stiffness = rng.uniform(0.0, 50.0);
      b.damping = rng.uniform(0.0, 2.0);
      b.spring_reference = rng.uniform(-0.3, 0.3);
      s.bodies.push_back(b);
    }
    s.gravity = 9.81 * rng.unit();
    trees.push_back(make_tree(s));
  }
  return trees;
}

// (nv x W) lane-innermost array from per-lane vectors, and back.
std::vector<double> gather(const std::vector<VectorXd>& x) {
  const int W = static_cast<int>(x.size()), nv = static_cast<int>(x[0].size());
  std::vector<double> out(static_cast<std::size_t>(nv) * W);
  for (int l = 0; l < W; ++l)
    for (int j = 0; j < nv; ++j) out[static_cast<std::size_t>(j) * W + l] = x[static_cast<std::size_t>(l)][j];
  return out;
}
VectorXd lane(const std::vector<double>& x, int nv, int W, int l) {
  VectorXd v(nv);
  for (int j = 0; j < nv; ++j) v[j] = x[static_cast<std::size_t>(j) * W + l];
  return v;
}

// qdd of W lanes of random trees (random_lanes) at random states, springs in tau and an extra armature
// when with_arm, against the scalar ABA per lane (with tau + passive forces, the armature added to the
// trees' own): the largest relative difference.
double lanes_against_scalar(test::Rng& rng, int n, int W, bool coordinate_axes, bool with_arm) {
  const std::vector<Tree> trees = random_lanes(rng, n, W, coordinate_axes);
  const TreeLanes tl = make_tree_lanes(trees);
  const int nv = tl.nv;
  std::vector<VectorXd> q, qd, tau, arm;
  for (const Tree& tr : trees) {
    q.push_back(test::random_q(rng, tr));
    qd.push_back(test::random_vector(rng, nv, -2.0, 2.0));
    tau.push_back(test::random_vector(rng, nv, -5.0, 5.0));
    arm.push_back(test::random_vector(rng, nv, 0.0, 0.5));
  }
  const std::vector<double> Q = gather(q), QD = gather(qd), TA = gather(tau), AR = gather(arm);
  std::vector<double> total(Q.size()), qdd(Q.size());
  compute_tree_passive_forces(tl, Q.data(), QD.data(), TA.data(), total.data());
  TreeLanesWorkspace ws(tl);
  compute_tree_forward_dynamics(tl, Q.data(), QD.data(), total.data(), with_arm ? AR.data() : nullptr, qdd.data(),
                                ws);
  double worst = 0.0;
  for (int l = 0; l < W; ++l) {
    const Tree& tr = trees[static_cast<std::size_t>(l)];
    TreeSpec s = test::spec_of(tr);
    for (BodySpec& b : s.bodies) b.stiffness = b.damping = 0.0;
    for (int i = 0; i < tr.num_bodies(); ++i)
      if (with_arm && tr.body(i).dof >= 0)
        s.bodies[static_cast<std::size_t>(i)].armature += arm[static_cast<std::size_t>(l)][tr.body(i).dof];
    const Tree oracle = make_tree(s);
    VectorXd passive(nv), expect(nv);
    calc_passive_forces(tr, q[static_cast<std::size_t>(l)], qd[static_cast<std::size_t>(l)], passive);
    TreeWorkspace tws(oracle);
    calc_forward_dynamics(oracle, q[static_cast<std::size_t>(l)], qd[static_cast<std::size_t>(l)],
                          passive + tau[static_cast<std::size_t>(l)], expect, tws);
    worst = std::max(worst, test::rel_diff(lane(qdd, nv, W, l), expect));
  }
  return worst;
}

TEST(TreeLanes, ForwardDynamicsMatchesTheScalarAbaInEveryLaneOfRandomTrees) {
  // 40 random topologies of 1..12 bodies, 5 lanes each with their own parameters and states,
  // springs in tau, and an extra armature in half of them: qdd within 1e-12 of the scalar ABA.
  test::Rng rng(20261202);
  double worst = 0.0;
  for (int t = 0; t < 40; ++t) {
    const double e = lanes_against_scalar(rng, 1 + t % 12, 5, false, t % 2 == 1);
    worst = std::max(worst, e);
    EXPECT_LT(e, 1e-12) << "topology " << t;
  }
  RecordProperty("worst_relative_difference", test::sci(worst));
}

TEST(TreeLanes, CoordinateAxesAndEveryCompiledWidthMatchTheScalarAba) {
  // The lane ABA turns each body's coordinates so that its joint axis is z (exactly for ±x, ±y, ±z) and
  // compiles W = 4, 8, 16 apart: 60 random topologies of 1..12 bodies, every joint type, axes ±x, ±y, ±z
  // and random ones mixed per lane, identity and random rotations, at W = 4, 8, 16 and 5: within 1e-12.
  test::Rng rng(20261204);
  double worst = 0.0;
  for (int t = 0; t < 60; ++t) {
    const int W = std::array{4, 8, 16, 5}[static_cast<std::size_t>(t % 4)];
    const double e = lanes_against_scalar(rng, 1 + t % 12, W, true, t % 3 == 1);
    worst = std::max(worst, e);
    EXPECT_LT(e, 1e-12) << "topology " << t << " W " << W;
  }
  RecordProperty("worst_relative_difference", test::sci(worst));
}

TEST(TreeLanes, AVariantGivesTheSameBitsInAnyLaneAtAnyWidth) {
  // One 3-D flexible link on a revolute-prismatic base (every joint type) at a random state, alone
  // (W = 1), then in lane 2 of 3, 3 of 4, 6 of 7, 0 and 5 of 8, 12 of 13 and 9 of 16 among other variants
  // (4, 8 and 16 compiled apart): qdd bit for bit.
  test::Rng rng(7);
  auto make = [](double scale) {
    TreeSpec s;
    BodySpec base;
    base.joint = JointType::kPrismatic;
    base.axis = Vec3::UnitX();
    base.mass = 20.0 * scale;
    base.inertia = test::box_inertia(base.mass, 0.5, 0.5, 0.3);
    s.bodies.push_back(base);
    BodySpec hub = base;
    hub.parent = 0;
    hub.joint = JointType::kRevolute;
    hub.axis = Vec3(0.1, 0.2, 1.0).normalized();
    hub.mass = 3.0;
    hub.inertia = test::box_inertia(3.0, 0.2, 0.2, 0.2);
    s.bodies.push_back(hub);
    FlexibleLinkSpec link;
    link.length = 1.5;
    link.section = {70e9, 26e9, 2700.0, 4e-4, 3e-8, 5e-8, 6e-8};
    link.segments = 5;
    link.damping_time = 1e-3;
    link.payload.mass = 2.0 * scale;
    append_flexible_link(s, 1, Vec3(0.1, 0.0, 0.05), Mat3::Identity(), link);
    return make_tree(s);
  };
  const Tree target = make(1.0);
  const int nv = target.nv();
  const VectorXd q = test::random_vector(rng, nv, -0.4, 0.4), qd = test::random_vector(rng, nv, -1.0, 1.0);
  const VectorXd tau = test::random_vector(rng, nv, -10.0, 10.0);
  auto run = [&](int W, int at) {
    std::vector<Tree> trees;
    std::vector<VectorXd> Q, QD, T;
    for (int l = 0; l < W; ++l) {
      trees.push_back(l == at ? target : make(0.5 + 0.1 * l));
      Q.push_back(l == at ? q : test::random_vector(rng, nv, -1.0, 1.0));
      QD.push_back(l == at ? qd : test::random_vector(rng, nv, -1.0, 1.0));
      T.push_back(l == at ? tau : test::random_vector(rng, nv, -1.0, 1.0));
    }
    const TreeLanes tl = make_tree_lanes(trees);
    TreeLanesWorkspace ws(tl);
    const std::vector<double> gq = gather(Q), gqd = gather(QD), gt = gather(T);
    std::vector<double> tot(gq.size()), qdd(gq.size());
    compute_tree_passive_forces(tl, gq.data(), gqd.data(), gt.data(), tot.data());
    compute_tree_forward_dynamics(tl, gq.data(), gqd.data(), tot.data(), nullptr, qdd.data(), ws);
    return lane(qdd, nv, W, at);
  };
  const VectorXd alone = run(1, 0);
  for (const auto& [W, at] : {std::pair{3, 2}, std::pair{4, 3}, std::pair{7, 6}, std::pair{8, 0}, std::pair{8, 5}, std::pair{13, 12},
                              std::pair{16, 9}}) {
    const VectorXd x = run(W, at);
    for (int j = 0; j < nv; ++j) EXPECT_EQ(x[j], alone[j]) << "W " << W << " lane " << at << " dof " << j;
  }
}

TEST(TreeLanes, PassiveForcesAreMinusStiffnessTimesStretchMinusDampingTimesRate) {
  test::Rng rng(3);
  const std::vector<Tree> trees = random_lanes(rng, 6, 4);
  const TreeLanes tl = make_tree_lanes(trees);
  std::vector<VectorXd> q, qd;
  for (const Tree& t : trees) q.push_back(test::random_q(rng, t)), qd.push_back(test::random_vector(rng, t.nv(), -1, 1));
  const std::vector<double> Q = gather(q), QD = gather(qd);
  std::vector<double> tau(Q.size());
  compute_tree_passive_forces(tl, Q.data(), QD.data(), nullptr, tau.data());
  for (int l = 0; l < tl.W; ++l) {
    VectorXd expect(tl.nv);
    calc_passive_forces(trees[static_cast<std::size_t>(l)], q[static_cast<std::size_t>(l)],
                        qd[static_cast<std::size_t>(l)], expect);
    EXPECT_EQ(lane(tau, tl.nv, tl.W, l), expect);
  }
}

TEST(TreeLanes, JointFrictionAddsTheStaticMapAtTheRateToThePassiveForcesOfItsDofOnly) {
  test::Rng rng(4);
  const std::vector<Tree> trees = random_lanes(rng, 6, 3);
  TreeLanes tl = make_tree_lanes(trees);
  std::vector<VectorXd> q, qd;
  for (const Tree& t : trees) q.push_back(test::random_q(rng, t)), qd.push_back(test::random_vector(rng, t.nv(), -1, 1));
  const std::vector<double> Q = gather(q), QD = gather(qd);
  std::vector<double> plain(Q.size()), with(Q.size());
  compute_tree_passive_forces(tl, Q.data(), QD.data(), nullptr, plain.data());
  // Lane 1 without friction (the zero map), lanes 0 and 2 with their own.
  std::vector<FrictionSpec> f(3);
  f[0].viscous = 0.3, f[0].coulomb = 0.2;
  f[2].coulomb = 0.5, f[2].stiction = 0.8, f[2].stribeck_velocity = 0.05, f[2].smoothing = 1e-2;
  const int d = tl.nv - 1;
  set_tree_lanes_friction(tl, d, f);
  ASSERT_EQ(tl.friction_dofs, std::vector<int>{d});
  compute_tree_passive_forces(tl, Q.data(), QD.data(), nullptr, with.data());
  for (int l = 0; l < tl.W; ++l)
    for (int j = 0; j < tl.nv; ++j) {
      const std::size_t k = static_cast<std::size_t>(j * tl.W + l);
      const double expect = j == d && l != 1 ? plain[k] + calc_friction_torque(make_friction_map(f[static_cast<std::size_t>(l)]), QD[k])
                                             : plain[k];
      EXPECT_EQ(with[k], expect) << "dof " << j << " lane " << l;
    }
  // -(0.3 w + 0.2 tanh(w / 1e-3)) at lane 0's rate.
  const double w0 = QD[static_cast<std::size_t>(d * tl.W)];
  EXPECT_NEAR(with[static_cast<std::size_t>(d * tl.W)] - plain[static_cast<std::size_t>(d * tl.W)],
              -(0.3 * w0 + 0.2 * std::tanh(w0 / 1e-3)), 1e-13);  // less the passive force it is added to
  // All-zero maps drop the dof; an unphysical map is refused.
  set_tree_lanes_friction(tl, d, std::vector<FrictionSpec>(3));
  EXPECT_TRUE(tl.friction_dofs.empty());
  EXPECT_TRUE(tl.friction.empty());
  f[1].coulomb = 1.0, f[1].stiction = 0.5;
  EXPECT_THROW(set_tree_lanes_friction(tl, d, f), std::invalid_argument);
  EXPECT_THROW(set_tree_lanes_friction(tl, tl.nv, std::vector<FrictionSpec>(3)), std::invalid_argument);
}

TEST(TreeLanes, ADriveLawAtATwistReplacesItsSpringAndLoadsItsRotorByTheEfficiency) {
  // The twist dof gets -T(q_t, qd_t) (kernel/drive.hpp, the rig's law) in place of -k (q - q0) - c qd;
  // the rotor dof T_t (1 - factor(eta, T_t qd_r)); every other dof as before.
  test::Rng rng(5);
  const std::vector<Tree> trees = random_lanes(rng, 6, 3);
  TreeLanes tl = make_tree_lanes(trees);
  std::vector<VectorXd> q, qd;
  for (const Tree& t : trees) q.push_back(test::random_q(rng, t)), qd.push_back(test::random_vector(rng, t.nv(), -1, 1));
  const int twist = tl.nv - 1, rotor = 0;
  ASSERT_GT(twist, rotor);
  q[1][twist] = 0.02;  // lane 1 inside its free play (b = 0.05)
  std::vector<double> Q = gather(q), QD = gather(qd);
  std::vector<double> plain(Q.size()), with(Q.size());
  compute_tree_passive_forces(tl, Q.data(), QD.data(), nullptr, plain.data());
  std::vector<LaneDrive> laws(3);
  for (int l = 0; l < 3; ++l) {
    laws[static_cast<std::size_t>(l)].k = 100.0 + 10.0 * l;
    laws[static_cast<std::size_t>(l)].c = 0.5;
  }
  laws[1].b = 0.05, laws[1].k3 = 1e4;
  laws[2].eta = 0.7, laws[2].k3 = 2e3;
  add_tree_lanes_transmission(tl, twist, rotor, laws);
  compute_tree_passive_forces(tl, Q.data(), QD.data(), nullptr, with.data());
  for (int l = 0; l < tl.W; ++l) {
    const Tree& t = trees[static_cast<std::size_t>(l)];
    const LaneDrive& p = laws[static_cast<std::size_t>(l)];
    const std::size_t o = static_cast<std::size_t>(twist * tl.W + l), r = static_cast<std::size_t>(rotor * tl.W + l);
    const double spring = -t.body(twist).stiffness * (Q[o] - t.body(twist).spring_reference) - t.body(twist).damping * QD[o];
    const double tt = -calc_transmission_torque(p, Q[o], QD[o]);
    EXPECT_NEAR(with[o], plain[o] - spring + tt, 1e-12 * (1.0 + std::abs(plain[o]))) << "lane " << l;
    const double rotor_share = p.eta == 1.0 ? 0.0 : tt * (1.0 - calc_efficiency_factor(p.eta, tt * QD[r]));
    EXPECT_EQ(with[r], plain[r] + rotor_share) << "lane " << l;
    for (int j = 1; j < twist; ++j)
      EXPECT_EQ(with[static_cast<std::size_t>(j * tl.W + l)], plain[static_cast<std::size_t>(j * tl.W + l)]) << j;
  }
  // Inside the free play nothing is transmitted; the linear law with k3 = 0 is the spring.
  EXPECT_NEAR(with[static_cast<std::size_t>(twist * tl.W + 1)] -
                (plain[static_cast<std::size_t>(twist * tl.W + 1)] + trees[1].body(twist).stiffness *
                     (Q[static_cast<std::size_t>(twist * tl.W + 1)] - trees[1].body(twist).spring_reference) +
                 trees[1].body(twist).damping * QD[static_cast<std::size_t>(twist * tl.W + 1)]),
            0.0, 1e-13);
  EXPECT_NEAR(-calc_transmission_torque(LaneDrive{.k = 100.0, .c = 0.5}, 0.3, -2.0), -(100.0 * 0.3 - 0.5 * 2.0), 1e-14);
  // A twist given twice, a count other than W, an efficiency above 1 are refused.
  EXPECT_THROW(add_tree_lanes_transmission(tl, twist, rotor, laws), std::invalid_argument);
  TreeLanes fresh = make_tree_lanes(trees);
  EXPECT_THROW(add_tree_lanes_transmission(fresh, twist, rotor, std::vector<LaneDrive>(2)), std::invalid_argument);
  laws[0].eta = 1.2;
  EXPECT_THROW(add_tree_lanes_transmission(fresh, twist, rotor, laws), std::invalid_argument);
}

TEST(TreeLanes, LugreBristlesAddSigma0ZPlusSigma1ZdotPlusBwAndTheirRate) {
  // tau_f = -(sigma0 z + sigma1 zdot + b w), zdot = w - sigma0 |w| z / g(w), g = Fc + (Fs - Fc) e^-(w/vs)^2.
  test::Rng rng(6);
  const std::vector<Tree> trees = random_lanes(rng, 4, 2);
  TreeLanes tl = make_tree_lanes(trees);
  const int d = 1;
  std::vector<FrictionSpec> f(2);
  for (FrictionSpec& x : f) x.model = "lugre", x.coulomb = 0.5, x.stiction = 0.8, x.stribeck_velocity = 0.1, x.viscous = 0.05;
  f[1].bristle_stiffness = 2.0e4, f[1].bristle_damping = 50.0;
  add_tree_lanes_lugre(tl, d, f);
  ASSERT_EQ(tl.nz(), 1);
  const std::vector<double> q(static_cast<std::size_t>(tl.nv * tl.W), 0.0);
  std::vector<double> qd(q.size(), 0.0), z{3.0e-5, -1.0e-5}, tau(q.size()), zdot(2);
  qd[static_cast<std::size_t>(d * tl.W)] = 0.07, qd[static_cast<std::size_t>(d * tl.W + 1)] = -0.3;
  compute_tree_actuator_forces(tl, q.data(), qd.data(), z.data(), nullptr, tau.data(), zdot.data());
  for (int l = 0; l < 2; ++l) {
    const FrictionSpec& x = f[static_cast<std::size_t>(l)];
    const double w = qd[static_cast<std::size_t>(d * tl.W + l)];
    const double g = x.coulomb + (x.stiction - x.coulomb) * std::exp(-(w / 0.1) * (w / 0.1));
    const double zd = w - x.bristle_stiffness * std::abs(w) * z[static_cast<std::size_t>(l)] / g;
    EXPECT_NEAR(zdot[static_cast<std::size_t>(l)], zd, 1e-14) << l;
    EXPECT_NEAR(tau[static_cast<std::size_t>(d * tl.W + l)],
                -(x.bristle_stiffness * z[static_cast<std::size_t>(l)] + x.bristle_damping * zd + x.viscous * w), 1e-12) << l;
    EXPECT_EQ(tau[static_cast<std::size_t>(l)], 0.0);  // other dofs: nothing
  }
}

TEST(TreeLanes, TreesOfAnotherTopologyAreRejectedNamingTheLaneAndBody) {
  test::Rng rng(11);
  std::vector<Tree> trees = random_lanes(rng, 4, 2);
  TreeSpec s;
  for (int i = 0; i < 4; ++i) s.bodies.push_back(test::random_body(rng, i - 1, nullptr));
  s.bodies[2].joint = trees[0].body(2).joint == JointType::kFixed ? JointType::kRevolute : JointType::kFixed;
  trees.push_back(make_tree(s));
  try {
    make_tree_lanes(trees);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lane 2, body"), std::string::npos) << e.what();
  }
  EXPECT_THROW(make_tree_lanes(std::vector<Tree>{}), std::invalid_argument);
}

}  // namespace
}  // namespace ff
