// The kinematic tree model (tree.hpp): validation of a TreeSpec and the derived bodies.
#include "multibody/tree.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "multibody/limits.hpp"

namespace ff {

namespace {

// "body 3 (\"forearm\")" or "body 3".
std::string label(int i, const BodySpec& b) {
  std::string s = "body " + std::to_string(i);
  if (!b.name.empty()) s += " (\"" + b.name + "\")";
  return s;
}

[[noreturn]] void fail(int i, const BodySpec& b, const std::string& what) {
  throw std::invalid_argument("tree: " + label(i, b) + ": " + what);
}

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

bool finite(const Vec3& v) { return v.allFinite(); }
bool finite(const Mat3& m) { return m.allFinite(); }

// A proper rotation: R^T R = I and det R = +1, to round-off of the user's numbers.
void check_rotation(int i, const BodySpec& b) {
  if (!finite(b.rotation)) fail(i, b, "joint frame rotation is not finite");
  const double orth = (b.rotation.transpose() * b.rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  if (orth > 1e-9 || b.rotation.determinant() <= 0.0)
    fail(i, b, "joint frame rotation is not a proper rotation matrix (R^T R = I, det R = +1 to 1e-9; off by " +
                   fmt(orth) + ")");
}

// The rotational inertia about the centre of mass: symmetric, positive definite for a body with
// mass (zero for a massless one), principal moments obeying the triangle inequality
// I_a + I_b >= I_c (every physical mass distribution does: I_a + I_b - I_c = 2 ∫ r_c² dm).
void check_inertia(int i, const BodySpec& b) {
  const Mat3& I = b.inertia;
  if (!finite(I)) fail(i, b, "inertia tensor is not finite");
  const double scale = std::max(I.cwiseAbs().maxCoeff(), 1e-300);
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale) fail(i, b, "inertia tensor is not symmetric");
  if (b.mass == 0.0) {
    if (I.cwiseAbs().maxCoeff() != 0.0) fail(i, b, "a massless body must have a zero inertia tensor");
    return;
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(I, Eigen::EigenvaluesOnly);
  const Vec3 p = eig.eigenvalues();  // ascending
  const std::string moments = " (principal moments " + fmt(p[0]) + ", " + fmt(p[1]) + ", " + fmt(p[2]) + " kg·m²)";
  if (!(p[0] > 0.0)) fail(i, b, "inertia tensor is not positive definite" + moments);
  // The largest against the other two; a flat plate sits on the boundary (I_z = I_x + I_y).
  if (p[2] > p[0] + p[1] + 1e-10 * p.sum())
    fail(i, b, "inertia tensor violates the triangle inequality I_a + I_b >= I_c" + moments);
}

void check_body(int i, const BodySpec& b) {
  if (b.parent < -1) fail(i, b, "parent " + std::to_string(b.parent) + " is out of range (-1 = the base)");
  if (b.parent >= i)
    fail(i, b, "parent " + std::to_string(b.parent) +
                   " comes after its child (bodies must be in topological order: parent index < own index)");
  if (b.joint != JointType::kFixed) {
    if (!finite(b.axis)) fail(i, b, "joint axis is not finite");
    if (!(b.axis.norm() > 1e-12)) fail(i, b, "joint axis is zero");
  }
  if (!finite(b.position)) fail(i, b, "joint frame position is not finite");
  check_rotation(i, b);
  if (!std::isfinite(b.mass)) fail(i, b, "mass is not finite");
  if (b.mass < 0.0) fail(i, b, "mass " + fmt(b.mass) + " kg is negative");
  if (!std::isfinite(b.armature) || b.armature < 0.0)
    fail(i, b, "armature " + fmt(b.armature) + " must be non-negative and finite");
  if (!std::isfinite(b.stiffness) || b.stiffness < 0.0)
    fail(i, b, "stiffness " + fmt(b.stiffness) + " must be non-negative and finite");
  if (!std::isfinite(b.damping) || b.damping < 0.0)
    fail(i, b, "damping " + fmt(b.damping) + " must be non-negative and finite");
  if (!std::isfinite(b.spring_reference)) fail(i, b, "spring reference is not finite");
  if (!finite(b.com)) fail(i, b, "centre of mass is not finite");
  check_inertia(i, b);
}

}  // namespace

SpatialMotion Tree::base_acceleration() const {
  SpatialMotion a = SpatialMotion::Zero();
  a.tail<3>() = -gravity_;
  return a;
}

std::string tree_size_fault(std::size_t bodies) {
  if (bodies <= static_cast<std::size_t>(kMaxTreeBodies)) return "";
  return "the tree has " + std::to_string(bodies) + " bodies (flexible links' segments and joint bodies counted), "
         "over the limit of " + std::to_string(kMaxTreeBodies);
}

Tree make_tree(const TreeSpec& spec) {
  if (!finite(spec.gravity)) throw std::invalid_argument("tree: gravity is not finite");
  if (const std::string fault = tree_size_fault(spec.bodies.size()); !fault.empty()) throw std::invalid_argument(fault);
  Tree t;
  t.gravity_ = spec.gravity;
  t.bodies_.reserve(spec.bodies.size());
  for (std::size_t k = 0; k < spec.bodies.size(); ++k) {
    const int i = static_cast<int>(k);
    const BodySpec& s = spec.bodies[k];
    check_body(i, s);
    Body b;
    b.name = s.name;
    b.parent = s.parent;
    b.joint = s.joint;
    b.X_tree = Transform::from_pose(s.rotation, s.position);
    b.mass = s.mass;
    b.com = s.com;
    b.inertia_com = 0.5 * (s.inertia + s.inertia.transpose());
    b.inertia = spatial_inertia(s.mass, s.com, b.inertia_com);
    if (s.joint != JointType::kFixed) {
      b.dof = t.nv_++;
      b.axis = s.axis.normalized();
      b.armature = s.armature;
      b.stiffness = s.stiffness;
      b.damping = s.damping;
      b.spring_reference = s.spring_reference;
      if (s.joint == JointType::kRevolute)
        b.S.head<3>() = b.axis;
      else
        b.S.tail<3>() = b.axis;
    }
    t.bodies_.push_back(std::move(b));
  }
  return t;
}

}  // namespace ff
