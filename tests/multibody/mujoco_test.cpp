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
//
// Trajectories (TrajectoryMatchesMuJoCoRk4): the arm with armature, joint springs and dampers and a
// constant applied torque (qfrc_applied), 2 s by flexfarm's lane RK4 (W = 1 and W = 4) and MuJoCo's
// RK4 at the same step; they agree far inside the integrator's own error, and M(q) along the way.
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

#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "multibody/lane_integrators.hpp"
#include "multibody/lanes.hpp"
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

// Joint drive of the trajectory test: armature, passive spring (about q_ref) and damper per joint.
struct JointDrive {
  double armature[6] = {0.05, 0.08, 0.03, 0.01, 0.005, 0.002};   // kg·m²
  double stiffness[6] = {30.0, 60.0, 40.0, 6.0, 4.0, 1.5};       // N·m/rad
  double damping[6] = {0.8, 1.2, 0.6, 0.08, 0.05, 0.01};         // N·m·s/rad
  double q_ref[6] = {0.3, -0.6, 0.9, 0.2, -0.4, 0.5};            // rad: the springs' reference
};

Tree arm_tree(const JointDrive* drive = nullptr) {
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
    if (drive) {
      b.armature = drive->armature[i];
      b.stiffness = drive->stiffness[i];
      b.damping = drive->damping[i];
      b.spring_reference = drive->q_ref[i];
    }
    s.bodies.push_back(b);
  }
  return make_tree(s);
}

// The same arm in MJCF: nested bodies at the joint frames (pos, quat), one hinge at each body's
// origin, <inertial> with diaginertia and the principal frame's quat, or (as_full) with
// fullinertia="Ixx Iyy Izz Ixy Ixz Iyz". Nothing added by MuJoCo: no armature, damping, friction
// loss, stiffness or contact, unless `drive` gives each joint its armature, stiffness (springref)
// and damping; `integrator` and `timestep` go to <option>.
std::string arm_mjcf(bool as_full, const JointDrive* drive = nullptr, const char* integrator = "Euler",
                     double timestep = 0.001) {
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco model=\"arm6\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"0 0 -9.81\" timestep=\"" << timestep << "\" integrator=\"" << integrator << "\">\n"
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
      << l.axis.y() << ' ' << l.axis.z() << '"';
    if (drive)
      x << " armature=\"" << drive->armature[i] << "\" stiffness=\"" << drive->stiffness[i] << "\" springref=\""
        << drive->q_ref[i] << "\" damping=\"" << drive->damping[i] << '"';
    x << "/>\n";
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
  void load(bool as_full, const JointDrive* drive = nullptr, const char* integrator = "Euler", double timestep = 0.001) {
    data_.reset();
    model_ = load_mjcf(arm_mjcf(as_full, drive, integrator, timestep));
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

// Two simulators' trajectories against the step's own error (RK4, by step halving): it is resolved
// (below 1e-6) and they agree within it, or within rounding (1e-12) where the step's error is below that.
void expect_within_integrator_error(double diff, double est) {
  EXPECT_LT(est, 1e-6);
  EXPECT_LT(diff, 1e-6);
  EXPECT_LT(diff, std::max(est, 1e-12));
}

// flexfarm's lane RK4 over `seconds` at step h in W identical lanes from (q0, qd0) with the constant
// applied torque tau; the joint angles of every lane at every `every`-th step (rows: samples, then
// W blocks of nv).
std::vector<Eigen::VectorXd> lane_rk4_trajectory(const Tree& tree, int W, double h, long steps, long every,
                                                 const Eigen::VectorXd& q0, const Eigen::VectorXd& qd0,
                                                 const Eigen::VectorXd& tau) {
  const std::vector<Tree> trees(static_cast<std::size_t>(W), tree);
  const TreeLanes tl = make_tree_lanes(trees);
  TreeLanesState st = make_tree_lanes_state(tl);
  TreeStepWorkspace ws(tl);
  const int nv = tl.nv;
  std::vector<double> tau_l(static_cast<std::size_t>(nv) * W);
  for (int j = 0; j < nv; ++j)
    for (int l = 0; l < W; ++l) {
      st.q[j * W + l] = q0[j];
      st.qd[j * W + l] = qd0[j];
      tau_l[j * W + l] = tau[j];
    }
  std::vector<Eigen::VectorXd> out;
  auto record = [&] {
    Eigen::VectorXd row(nv * W);
    for (int l = 0; l < W; ++l)
      for (int j = 0; j < nv; ++j) row[l * nv + j] = st.q[j * W + l];
    out.push_back(row);
  };
  record();
  for (long k = 1; k <= steps; ++k) {
    step_tree_rk4(tl, tau_l.data(), st, ws, h);
    if (k % every == 0) record();
  }
  return out;
}

TEST_F(MuJoCoArm, TrajectoryMatchesMuJoCoRk4) {
  // The arm with armature, joint springs about q_ref and dampers, under gravity, with the constant
  // torque that holds it at q_ref (RNEA at q_ref, gravity compensation; qfrc_applied in MuJoCo);
  // from q_ref + offsets at a swing it oscillates in 3-D, damped, for 2 s. Both simulators take
  // classical RK4 with the torque held over the step, h = 1e-4 s: flexfarm's lanes (W = 1, and
  // W = 4 identical lanes, the same bits) and MuJoCo's RK4 (contacts off, no limits).
  const JointDrive drive;
  load(false, &drive, "RK4", 1e-4);
  const Tree tree = arm_tree(&drive);
  ASSERT_EQ(model_->opt.integrator, mjINT_RK4);
  for (int i = 0; i < 6; ++i) {
    ASSERT_EQ(model_->dof_armature[i], drive.armature[i]);
    ASSERT_EQ(model_->jnt_stiffness[i], drive.stiffness[i]);
    ASSERT_EQ(model_->dof_damping[i], drive.damping[i]);
    ASSERT_EQ(model_->qpos_spring[i], drive.q_ref[i]);
  }
  const Eigen::VectorXd q_ref = Eigen::Map<const Eigen::VectorXd>(drive.q_ref, 6);
  Eigen::VectorXd tau(6);
  TreeWorkspace tws(tree);
  calc_bias_forces(tree, q_ref, Eigen::VectorXd::Zero(6), tau, tws);  // g(q_ref)
  Eigen::VectorXd q0(6), qd0(6);
  q0 << 0.7, -0.2, 0.4, 0.9, -1.0, 1.2;
  qd0 << 0.5, -0.8, 1.0, -1.5, 2.0, -2.5;

  const double h = 1e-4, seconds = 2.0;
  const long steps = std::lround(seconds / h), every = 500;  // a sample every 50 ms
  const auto ff1 = lane_rk4_trajectory(tree, 1, h, steps, every, q0, qd0, tau);
  const auto ff4 = lane_rk4_trajectory(tree, 4, h, steps, every, q0, qd0, tau);
  const auto ff_half = lane_rk4_trajectory(tree, 1, h / 2, 2 * steps, 2 * every, q0, qd0, tau);
  ASSERT_EQ(ff1.size(), static_cast<std::size_t>(steps / every + 1));

  // MuJoCo, sampled at the same steps; its mass matrix against flexfarm's at MuJoCo's q every 0.25 s.
  mj_resetData(model_.get(), data_.get());
  for (int j = 0; j < 6; ++j) {
    data_->qpos[j] = q0[j];
    data_->qvel[j] = qd0[j];
    data_->qfrc_applied[j] = tau[j];
  }
  std::vector<Eigen::VectorXd> mj{Eigen::Map<const Eigen::VectorXd>(data_->qpos, 6)};
  Eigen::MatrixXd M(6, 6);
  double worst_M = 0.0, swing = 0.0;
  int mass_checks = 0;
  for (long k = 1; k <= steps; ++k) {
    mj_step(model_.get(), data_.get());
    if (k % every) continue;
    const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(data_->qpos, 6);
    mj.push_back(q);
    swing = std::max(swing, (q - q_ref).cwiseAbs().maxCoeff());
    if (k % (5 * every) == 0) {
      mj_forward(model_.get(), data_.get());  // qM at this state (RK4 leaves its last stage's)
      Eigen::Matrix<double, 6, 6, Eigen::RowMajor> full;
      mj_fullM(model_.get(), full.data(), data_->qM);
      calc_mass_matrix(tree, q, M, tws);
      const double rel = test::rel_diff(M, Eigen::MatrixXd(full));
      worst_M = std::max(worst_M, rel);
      ++mass_checks;
      EXPECT_LT(rel, 1e-12) << "t = " << k * h << " s\nflexfarm\n" << M << "\nMuJoCo\n" << full;
    }
  }
  EXPECT_EQ(mass_checks, 8);
  for (int w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC}) EXPECT_EQ(data_->warning[w].number, 0);
  ASSERT_EQ(mj.size(), ff1.size());

  // The integrator's own error, by step halving: RK4's global error ~ C h^4, so
  // |q_h - q_h/2| (16/15) estimates that of q_h.
  double diff = 0.0, est = 0.0;
  for (std::size_t s = 0; s < ff1.size(); ++s) {
    for (int l = 0; l < 4; ++l)
      for (int j = 0; j < 6; ++j) ASSERT_EQ(ff4[s][l * 6 + j], ff1[s][j]) << "lane " << l << " sample " << s;
    diff = std::max(diff, (ff1[s] - mj[s]).cwiseAbs().maxCoeff());
    est = std::max(est, (ff1[s] - ff_half[s]).cwiseAbs().maxCoeff() * 16.0 / 15.0);
  }
  // It moves (a swing of about a radian), the step is resolved (error estimate < 1e-6 rad), and the
  // two simulators agree within it (measured: diff 1.7e-15 rad, est 5.7e-13 rad: both are the same
  // classical RK4 of the same equations, so they differ by rounding only; M along the way 1.4e-15).
  EXPECT_GT(swing, 0.5);
  expect_within_integrator_error(diff, est);
  RecordProperty("max_joint_difference_rad", test::sci(diff));
  RecordProperty("rk4_error_estimate_rad", test::sci(est));
  RecordProperty("worst_relative_difference_M", test::sci(worst_M));
}


// ---- The dual-arm tree of configs/sers.yaml (docs/sers.md): a 5-DOF base (x, y prismatic, yaw, lift,
// torso pitch) carrying two 6-DOF arms, rigid (each forearm one segment) ----

// Any flexfarm tree as MJCF: nested bodies at the joint frames (pos and the active rotation's quat),
// a hinge or slide named j<dof> at each moving body's origin on its axis with its armature, spring and
// damper, <inertial> as the tensor's principal moments (diaginertia) and axes (quat, from Eigen's
// symmetric eigensolver: MuJoCo's own diagonalisation of fullinertia is good to ~1e-8 only, see the top).
std::string tree_mjcf(const Tree& tree, const char* integrator, double timestep) {
  std::ostringstream x;
  x.precision(17);
  const Vec3 g = tree.gravity();
  x << "<mujoco model=\"tree\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"false\"/>\n"
    << "  <option gravity=\"" << g.x() << ' ' << g.y() << ' ' << g.z() << "\" timestep=\"" << timestep
    << "\" integrator=\"" << integrator << "\">\n    <flag contact=\"disable\"/>\n  </option>\n"
    << "  <default><joint armature=\"0\" damping=\"0\" frictionloss=\"0\" stiffness=\"0\" limited=\"false\"/></default>\n"
    << "  <worldbody>\n";
  std::vector<std::vector<int>> children(static_cast<std::size_t>(tree.num_bodies()));
  std::vector<int> roots;
  for (int i = 0; i < tree.num_bodies(); ++i)
    (tree.body(i).parent < 0 ? roots : children[static_cast<std::size_t>(tree.body(i).parent)]).push_back(i);
  const auto quat = [](const Mat3& R) {
    const Eigen::Quaterniond q(R);
    std::ostringstream o;
    o.precision(17);
    o << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z();
    return o.str();
  };
  // MuJoCo refuses a massless moving body, but takes several joints in one body, applied in order at the
  // body's origin: a massless body whose one child sits at its origin unturned (the SERS's carriages, a
  // planar joint's coordinates) is written as its joint inside that child.
  const auto merged = [&](int i) {
    const Body& b = tree.body(i);
    const std::vector<int>& c = children[static_cast<std::size_t>(i)];
    return b.mass == 0.0 && c.size() == 1 && tree.body(c[0]).X_tree.r.isZero(0.0) &&
           tree.body(c[0]).X_tree.E.isIdentity(0.0);
  };
  const auto joint = [&](const Body& b, const std::string& indent) {
    if (b.dof >= 0)
      x << indent << "  <joint name=\"j" << b.dof << "\" type=\"" << (b.joint == JointType::kPrismatic ? "slide" : "hinge")
        << "\" pos=\"0 0 0\" axis=\"" << b.axis.x() << ' ' << b.axis.y() << ' ' << b.axis.z() << "\" armature=\""
        << b.armature << "\" stiffness=\"" << b.stiffness << "\" springref=\"" << b.spring_reference << "\" damping=\""
        << b.damping << "\"/>\n";
  };
  const auto write = [&](const auto& self, int i, const std::string& indent) -> void {
    // The chain of merged massless bodies from i down to the body that carries their joints and mass.
    std::vector<int> chain{i};
    while (merged(chain.back())) chain.push_back(children[static_cast<std::size_t>(chain.back())][0]);
    const Vec3 p = tree.body(i).X_tree.r;
    x << indent << "<body name=\"" << tree.body(chain.back()).name << "\" pos=\"" << p.x() << ' ' << p.y() << ' ' << p.z()
      << "\" quat=\"" << quat(tree.body(i).X_tree.E.transpose()) << "\">\n";
    for (int k : chain) joint(tree.body(k), indent);
    i = chain.back();
    const Body& b = tree.body(i);
    if (b.mass > 0) {
      const Eigen::SelfAdjointEigenSolver<Mat3> eig(b.inertia_com);
      Mat3 V = eig.eigenvectors();
      if (V.determinant() < 0) V.col(0) = -V.col(0);
      const Vec3 d = eig.eigenvalues();
      x << indent << "  <inertial pos=\"" << b.com.x() << ' ' << b.com.y() << ' ' << b.com.z() << "\" mass=\"" << b.mass
        << "\" quat=\"" << quat(V) << "\" diaginertia=\"" << d.x() << ' ' << d.y() << ' ' << d.z() << "\"/>\n";
    }
    for (int c : children[static_cast<std::size_t>(i)]) self(self, c, indent + "  ");
    x << indent << "</body>\n";
  };
  for (int r : roots) write(write, r, "    ");
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

// configs/sers.yaml with RK4 and a fixed number of substeps, run for `duration` s (its Cartesian move of
// both tools under way), keeping the full state.
ArmModel sers_model(double duration, int substeps) {
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/sers.yaml";
  YAML::Node doc = load_yaml_file(path);
  doc["simulation"]["integrator"] = "rk4";
  doc["simulation"]["substeps"] = substeps;
  doc["simulation"]["duration"] = duration;
  return parse_arm(doc, path);
}

TEST(MuJoCoSers, TheDualArmTreesMassMatrixMatchesMjFullM) {
  const ArmModel m = sers_model(1.0, 4);
  const Tree& tree = m.tree;
  ASSERT_EQ(tree.nv(), 17);  // 5 base + 2 x 6 arm joints (rigid forearms: no cells)
  const auto model = load_mjcf(tree_mjcf(tree, "RK4", 1e-3));
  std::unique_ptr<mjData, DataDeleter> data(mj_makeData(model.get()));
  ASSERT_EQ(model->nv, 17);
  test::Rng rng(1206);
  TreeWorkspace ws(tree);
  Eigen::MatrixXd M(17, 17);
  double worst = 0.0;
  for (int s = 0; s < 8; ++s) {
    Eigen::VectorXd q = test::random_q(rng, tree);
    for (int j = 0; j < 17; ++j) data->qpos[model->jnt_qposadr[mj_name2id(model.get(), mjOBJ_JOINT, ("j" + std::to_string(j)).c_str())]] = q[j];
    mj_forward(model.get(), data.get());
    Eigen::Matrix<double, 17, 17, Eigen::RowMajor> full;
    mj_fullM(model.get(), full.data(), data->qM);
    calc_mass_matrix(tree, q, M, ws);
    const double rel = test::rel_diff(M, Eigen::MatrixXd(full));
    worst = std::max(worst, rel);
    EXPECT_LT(rel, 1e-12) << "state " << s;
  }
  RecordProperty("worst_relative_difference_M", test::sci(worst));
}

TEST(MuJoCoSers, TheDualArmTreeFollowsMuJoCoOnTheCoordinatedMoveWithinTheIntegratorsError) {
  // flexfarm's closed-loop run of configs/sers.yaml (gravity, 17 PD joints with feed-forward, both tools
  // moving to their Cartesian targets together, RK4 at 4 substeps per 2 ms sample); the torques it
  // held at each sample (its trace's <joint>.torque) replayed open-loop into MuJoCo's RK4 at the same
  // step. The two agree far inside the integrator's error (MuJoCo at h against h/2).
  const double seconds = 2.0;
  const int substeps = 4;
  const ArmModel m = sers_model(seconds, substeps);
  const ArmRun run = simulate_arms(std::span<const ArmModel>(&m, 1), {.keep_q = true});
  ASSERT_EQ(run.status[0], LaneStatus::kOk);
  const ArmTrace& tr = run.traces[0];
  const Eigen::MatrixXd& qf = run.q[0];
  const long samples = static_cast<long>(tr.t().size());
  const int nv = m.tree.nv();
  auto replay = [&](int per_sample) {
    const auto model = load_mjcf(tree_mjcf(m.tree, "RK4", m.control_period / per_sample));
    std::unique_ptr<mjData, DataDeleter> data(mj_makeData(model.get()));
    std::vector<int> qadr(static_cast<std::size_t>(nv)), vadr(qadr);
    for (int j = 0; j < nv; ++j) {
      const int id = mj_name2id(model.get(), mjOBJ_JOINT, ("j" + std::to_string(j)).c_str());
      qadr[static_cast<std::size_t>(j)] = model->jnt_qposadr[id];
      vadr[static_cast<std::size_t>(j)] = model->jnt_dofadr[id];
    }
    for (int j = 0; j < nv; ++j) data->qpos[qadr[static_cast<std::size_t>(j)]] = m.q0[j];
    Eigen::MatrixXd out(nv, samples);
    for (long k = 0; k < samples; ++k) {
      for (int j = 0; j < nv; ++j) out(j, k) = data->qpos[qadr[static_cast<std::size_t>(j)]];
      for (const ActuatedJoint& a : m.actuated)
        data->qfrc_applied[vadr[static_cast<std::size_t>(a.dof)]] = tr.column(a.name + ".torque")[static_cast<std::size_t>(k)];
      for (int s = 0; s < per_sample; ++s) mj_step(model.get(), data.get());
    }
    for (int w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC}) EXPECT_EQ(data->warning[w].number, 0);
    return out;
  };
  const Eigen::MatrixXd mj = replay(substeps), mj_half = replay(2 * substeps);
  const double diff = (qf - mj).cwiseAbs().maxCoeff();
  const double est = (mj - mj_half).cwiseAbs().maxCoeff() * 16.0 / 15.0;  // RK4: error ~ C h^4
  // It moves: both tools travel to their targets (the left tool's reference moves by decimetres).
  double travel = 0.0;
  for (const char* c : {"left.x", "left.y", "left.z"})
    travel = std::max(travel, std::abs(tr.column(c).back() - tr.column(c).front()));
  EXPECT_GT(travel, 0.1);
  expect_within_integrator_error(diff, est);
  RecordProperty("max_joint_difference", test::sci(diff));
  RecordProperty("rk4_error_estimate", test::sci(est));
  RecordProperty("left_tool_travel_m", test::sci(travel));
}
}  // namespace
}  // namespace ff

#else

TEST(MuJoCoArm, Oracle) { GTEST_SKIP() << "built without MuJoCo (libmujoco-dev): the oracle tests are left out"; }

#endif
