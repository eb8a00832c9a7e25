// MuJoCo (2.2, Debian's libmujoco-dev) as an oracle for multibody/algorithms: a rigid 6-DOF arm
// (hinges about z, y, y, x, y, x; offset and turned joint frames; full inertias: diagonal principal
// moments in a rotated principal frame) built both as a flexfarm Tree and as MJCF; mj_fullM's mass
// matrix against calc_mass_matrix and qfrc_bias (after mj_forward, gravity on) against
// calc_bias_forces at random states. Built only when MuJoCo is found (tests/CMakeLists.txt).
//
// The MJCF gives each inertia as diaginertia + the principal frame's quat: MuJoCo then uses the
// numbers written. Given as fullinertia, MuJoCo's compiler diagonalises the tensor itself (mju_eig3:
// Jacobi rotations that stop at an off-diagonal below 1e-12 or a rotation cosine above 1 - 1e-12,
// i.e. a rotation left of up to ~1e-6 rad), so its body inertias are only good to ~1e-8 relative and
// the mass matrices agree to ~1e-10, not 1e-12 (FullInertiaFormAgreesToTheCompilersDiagonalisation).
#include <gtest/gtest.h>

#ifdef FLEXFARM_WITH_MUJOCO

#include <mujoco/mujoco.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstring>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "multibody/algorithms.hpp"
#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

// The arm: joint frame placement (position, rotation in the parent's frame), hinge axis, mass,
// centre of mass, principal moments and the rotation of the principal axes.
struct Link {
  Vec3 position;
  Mat3 rotation;
  Vec3 axis;
  double mass;
  Vec3 com;
  Vec3 principal;
  Mat3 principal_axes;
};

std::vector<Link> arm_links() {
  return {
      {{0.0, 0.0, 0.12}, Mat3::Identity(), Vec3::UnitZ(), 4.0, {0.01, -0.02, 0.08}, {0.030, 0.025, 0.020},
       rotz(0.3) * rotx(0.2)},
      {{0.0, 0.06, 0.18}, rotx(0.15), Vec3::UnitY(), 3.2, {0.20, 0.01, 0.02}, {0.010, 0.060, 0.055},
       roty(-0.4) * rotz(0.1)},
      {{0.42, 0.0, 0.03}, rotz(-0.25), Vec3::UnitY(), 2.1, {0.16, -0.015, 0.0}, {0.006, 0.030, 0.028},
       rotx(0.5) * roty(0.2)},
      {{0.36, 0.02, -0.01}, roty(0.3), Vec3::UnitX(), 1.1, {0.05, 0.0, 0.01}, {0.004, 0.003, 0.0035},
       rotz(0.7)},
      {{0.09, 0.0, 0.015}, Mat3::Identity(), Vec3::UnitY(), 0.8, {0.02, 0.01, -0.01}, {0.0015, 0.0012, 0.0010},
       rotx(-0.6) * rotz(0.4)},
      {{0.07, -0.01, 0.0}, rotx(-0.35), Vec3::UnitX(), 0.4, {0.03, 0.0, 0.005}, {0.0004, 0.0006, 0.0005},
       roty(0.9)},
  };
}

Mat3 full_inertia(const Link& l) { return l.principal_axes * l.principal.asDiagonal() * l.principal_axes.transpose(); }

Tree arm_tree() {
  TreeSpec s;
  const std::vector<Link> links = arm_links();
  for (std::size_t i = 0; i < links.size(); ++i) {
    const Link& l = links[i];
    BodySpec b;
    b.name = "link" + std::to_string(i + 1);
    b.parent = static_cast<int>(i) - 1;
    b.axis = l.axis;
    b.position = l.position;
    b.rotation = l.rotation;
    b.mass = l.mass;
    b.com = l.com;
    b.inertia = full_inertia(l);
    s.bodies.push_back(b);
  }
  return make_tree(s);
}

// The same arm in MJCF: nested bodies at the joint frames (pos, quat), one hinge at each body's
// origin, <inertial> with diaginertia and the principal frame's quat, or (as_full) with
// fullinertia="Ixx Iyy Izz Ixy Ixz Iyz". Nothing added by MuJoCo: no armature, damping, friction
// loss, stiffness or contact.
std::string arm_mjcf(bool as_full) {
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"arm6\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"0 0 -9.81\" timestep=\"0.001\" integrator=\"Euler\">\n"
    << "    <flag contact=\"disable\"/>\n  </option>\n"
    << "  <default><joint armature=\"0\" damping=\"0\" frictionloss=\"0\" stiffness=\"0\" limited=\"false\"/></default>\n"
    << "  <worldbody>\n";
  const std::vector<Link> links = arm_links();
  std::string indent = "    ";
  for (std::size_t i = 0; i < links.size(); ++i) {
    const Link& l = links[i];
    const Eigen::Quaterniond q(l.rotation), iq(l.principal_axes);
    const Mat3 I = full_inertia(l);
    x << indent << "<body name=\"link" << i + 1 << "\" pos=\"" << l.position.x() << ' ' << l.position.y() << ' '
      << l.position.z() << "\" quat=\"" << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << "\">\n";
    indent += "  ";
    x << indent << "<joint name=\"j" << i + 1 << "\" type=\"hinge\" pos=\"0 0 0\" axis=\"" << l.axis.x() << ' '
      << l.axis.y() << ' ' << l.axis.z() << "\"/>\n";
    x << indent << "<inertial pos=\"" << l.com.x() << ' ' << l.com.y() << ' ' << l.com.z() << "\" mass=\"" << l.mass;
    if (as_full)
      x << "\" fullinertia=\"" << I(0, 0) << ' ' << I(1, 1) << ' ' << I(2, 2) << ' ' << I(0, 1) << ' ' << I(0, 2) << ' '
        << I(1, 2) << "\"/>\n";
    else
      x << "\" quat=\"" << iq.w() << ' ' << iq.x() << ' ' << iq.y() << ' ' << iq.z() << "\" diaginertia=\""
        << l.principal.x() << ' ' << l.principal.y() << ' ' << l.principal.z() << "\"/>\n";
  }
  for (std::size_t i = 0; i < links.size(); ++i) {
    indent.resize(indent.size() - 2);
    x << indent << "</body>\n";
  }
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

// Compiles MJCF text through MuJoCo's virtual file system (no temporary file).
struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
std::unique_ptr<mjModel, ModelDeleter> load_mjcf(const std::string& xml) {
  auto vfs = std::make_unique<mjVFS>();  // ~2 MB: heap, not stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), "arm6.xml", static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("mj_makeEmptyFileVFS failed");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "arm6.xml")], xml.data(), xml.size());
  char err[1000] = "";
  mjModel* m = mj_loadXML("arm6.xml", vfs.get(), err, sizeof err);
  mj_deleteVFS(vfs.get());
  if (!m) throw std::runtime_error(std::string("mj_loadXML: ") + err);
  return std::unique_ptr<mjModel, ModelDeleter>(m);
}

class MuJoCoArm : public ::testing::Test {
 protected:
  void SetUp() override { load(false); }
  void load(bool as_full) {
    data_.reset();
    model_ = load_mjcf(arm_mjcf(as_full));
    data_.reset(mj_makeData(model_.get()));
    ASSERT_EQ(model_->nv, 6);
    ASSERT_EQ(model_->nq, 6);
  }
  // MuJoCo at (q, qd): mass matrix and bias forces.
  void mujoco_at(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::MatrixXd& M, Eigen::VectorXd& bias) {
    for (int k = 0; k < 6; ++k) {
      data_->qpos[k] = q[k];
      data_->qvel[k] = qd[k];
    }
    mj_forward(model_.get(), data_.get());
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> full;
    mj_fullM(model_.get(), full.data(), data_->qM);
    M = full;
    bias = Eigen::Map<const Eigen::VectorXd>(data_->qfrc_bias, 6);
  }
  std::unique_ptr<mjModel, ModelDeleter> model_;
  std::unique_ptr<mjData, DataDeleter> data_;
  const Tree tree_ = arm_tree();
};

TEST_F(MuJoCoArm, CompiledBodiesAreTheOnesWritten) {
  // body_inertia in the frame body_iquat gives back the tensor flexfarm uses, and nothing is added
  // on the joints.
  const std::vector<Link> links = arm_links();
  for (int i = 0; i < 6; ++i) {
    const int id = i + 1;  // body 0 is the world
    EXPECT_EQ(model_->body_mass[id], links[i].mass);
    const Eigen::Quaterniond iq(model_->body_iquat[4 * id], model_->body_iquat[4 * id + 1],
                                model_->body_iquat[4 * id + 2], model_->body_iquat[4 * id + 3]);
    const Mat3 R = iq.normalized().toRotationMatrix();
    const Mat3 I = R * Vec3(model_->body_inertia[3 * id], model_->body_inertia[3 * id + 1],
                            model_->body_inertia[3 * id + 2]).asDiagonal() * R.transpose();
    EXPECT_LT((I - full_inertia(links[i])).cwiseAbs().maxCoeff() / links[i].principal.maxCoeff(), 1e-13)
        << "body " << id;
    EXPECT_EQ(model_->dof_armature[i], 0.0);
    EXPECT_EQ(model_->dof_damping[i], 0.0);
    EXPECT_EQ(model_->dof_frictionloss[i], 0.0);
  }
}

TEST_F(MuJoCoArm, MassMatrixMatchesMjFullM) {
  test::Rng rng(606);
  Eigen::MatrixXd M_mj, M(6, 6);
  Eigen::VectorXd bias_mj;
  TreeWorkspace ws(tree_);
  double worst = 0.0;
  for (int s = 0; s < 8; ++s) {
    const Eigen::VectorXd q = test::random_q(rng, tree_), qd = test::random_vector(rng, 6, -2.0, 2.0);
    mujoco_at(q, qd, M_mj, bias_mj);
    calc_mass_matrix(tree_, q, M, ws);
    const double rel = test::rel_diff(M, M_mj);
    worst = std::max(worst, rel);
    EXPECT_LT(rel, 1e-12) << "state " << s << "\nflexfarm\n" << M << "\nMuJoCo\n" << M_mj;
  }
  RecordProperty("worst_relative_difference", test::sci(worst));
}

TEST_F(MuJoCoArm, BiasForcesMatchQfrcBiasWithGravity) {
  test::Rng rng(607);
  Eigen::MatrixXd M_mj;
  Eigen::VectorXd bias_mj, bias(6);
  TreeWorkspace ws(tree_);
  double worst = 0.0;
  for (int s = 0; s < 8; ++s) {
    const Eigen::VectorXd q = test::random_q(rng, tree_), qd = test::random_vector(rng, 6, -3.0, 3.0);
    mujoco_at(q, qd, M_mj, bias_mj);
    calc_bias_forces(tree_, q, qd, bias, ws);
    const double rel = test::rel_diff(bias, bias_mj);
    worst = std::max(worst, rel);
    EXPECT_LT(rel, 1e-10) << "state " << s << "\nflexfarm " << bias.transpose() << "\nMuJoCo   " << bias_mj.transpose();
  }
  RecordProperty("worst_relative_difference", test::sci(worst));
}

TEST_F(MuJoCoArm, FullInertiaFormAgreesToTheCompilersDiagonalisation) {
  // The arm with fullinertia: MuJoCo's own eigen-decomposition of each tensor (see the top) leaves
  // it ~1e-8 off, so M and the bias agree to 1e-8 here (measured: ~2e-10).
  load(true);
  test::Rng rng(608);
  Eigen::MatrixXd M_mj, M(6, 6);
  Eigen::VectorXd bias_mj, bias(6);
  TreeWorkspace ws(tree_);
  double worst_M = 0.0, worst_bias = 0.0;
  for (int s = 0; s < 8; ++s) {
    const Eigen::VectorXd q = test::random_q(rng, tree_), qd = test::random_vector(rng, 6, -3.0, 3.0);
    mujoco_at(q, qd, M_mj, bias_mj);
    calc_mass_matrix(tree_, q, M, ws);
    calc_bias_forces(tree_, q, qd, bias, ws);
    worst_M = std::max(worst_M, test::rel_diff(M, M_mj));
    worst_bias = std::max(worst_bias, test::rel_diff(bias, bias_mj));
  }
  EXPECT_LT(worst_M, 1e-8);
  EXPECT_LT(worst_bias, 1e-8);
  RecordProperty("worst_relative_difference_M", test::sci(worst_M));
  RecordProperty("worst_relative_difference_bias", test::sci(worst_bias));
}

}  // namespace
}  // namespace ff

#else

TEST(MuJoCoArm, Oracle) { GTEST_SKIP() << "built without MuJoCo (libmujoco-dev): the oracle tests are left out"; }

#endif
