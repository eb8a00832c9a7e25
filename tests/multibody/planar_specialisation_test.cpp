// The planar reference rig's kernel (kernel/dynamics: the ABA in planar form) is the specialisation
// of the tree kernel (multibody/lanes) to a chain of z-axis joints: the rig's bodies, written as a
// 3-D tree from the model's own body table (mass, first moment, inertia about the joint, segment
// length), give the same accelerations at random states, torques and armatures, to 1e-12.
#include <gtest/gtest.h>

#include <vector>

#include "kernel/batch.hpp"
#include "kernel/dynamics.hpp"
#include "kernel/model.hpp"
#include "multibody/lanes.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

// Body i of the planar chain as a 3-D body: joint about z at (L_{i-1}, 0, 0) in its parent, centre
// of mass at (h/m, 0, 0), I_zz about it J - m (h/m)^2 (I_xx = I_yy = I_zz: they do not enter planar
// motion, and satisfy the triangle inequality).
Tree tree_of(const Model& m) {
  TreeSpec s;
  s.gravity = Vec3::Zero();
  for (int i = 0; i < m.nseg; ++i) {
    const BodyInertia& b = m.body[static_cast<std::size_t>(i)];
    BodySpec bs;
    bs.parent = i - 1;
    bs.position = Vec3(i == 0 ? 0.0 : m.seg_length[static_cast<std::size_t>(i - 1)], 0.0, 0.0);
    bs.mass = b.mass;
    bs.com = Vec3(b.first / b.mass, 0.0, 0.0);
    const double Jc = b.inertia - b.first * b.first / b.mass;
    bs.inertia = Vec3(Jc, Jc, Jc).asDiagonal();
    s.bodies.push_back(bs);
  }
  return make_tree(s);
}

TEST(PlanarSpecialisation, TheRigsKernelAndTheTreeKernelGiveTheSameAccelerations) {
  test::Rng rng(6);
  for (int N : {1, 2, 6, 24}) {
    std::vector<Model> models;
    std::vector<Tree> trees;
    const int W = 4;
    for (int l = 0; l < W; ++l) {
      ModelSpec spec;
      spec.segments = N;
      spec.payload_mass = 328.7 * (1.0 + 0.2 * l);
      spec.hub_inertia = 50.0 + 10.0 * l;
      spec.simulation.duration = 1.0;
      models.push_back(make_model(spec));
      trees.push_back(tree_of(models.back()));
    }
    const BatchModel bm = make_batch(models);
    Workspace ws = make_workspace(bm);
    const TreeLanes tl = make_tree_lanes(trees);
    TreeLanesWorkspace tws(tl);
    ASSERT_EQ(tl.nv, N);
    const std::size_t n = static_cast<std::size_t>(N) * W;
    for (int trial = 0; trial < 5; ++trial) {
      std::vector<double> q(n), v(n), tau(n), arm(n), a_rig(n), a_tree(n);
      for (std::size_t j = 0; j < n; ++j) {
        q[j] = rng.uniform(-0.8, 0.8);
        v[j] = rng.uniform(-2.0, 2.0);
        tau[j] = rng.uniform(-5e3, 5e3);
        arm[j] = rng.uniform(0.0, 20.0);
      }
      compute_forward_dynamics(bm, q.data(), v.data(), tau.data(), arm.data(), a_rig.data(), ws);
      compute_tree_forward_dynamics(tl, q.data(), v.data(), tau.data(), arm.data(), a_tree.data(), tws);
      double scale = 0.0, diff = 0.0;
      for (std::size_t j = 0; j < n; ++j) {
        scale = std::max(scale, std::abs(a_rig[j]));
        diff = std::max(diff, std::abs(a_rig[j] - a_tree[j]));
      }
      EXPECT_LT(diff, 1e-12 * scale) << "N " << N << " trial " << trial;
    }
  }
}

}  // namespace
}  // namespace ff
