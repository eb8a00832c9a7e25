// Flexible links as chains of rigid segments and elastic spherical joints (flexible_link.hpp): the
// reference rig's lumping (docs/reference-rig.md) in two bending planes and torsion.
#include "multibody/flexible_link.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "multibody/limits.hpp"

namespace ff {

namespace {

[[noreturn]] void fail(const FlexibleLinkSpec& link, const std::string& what) {
  throw std::invalid_argument("flexible link \"" + link.name + "\": " + what);
}

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

void positive(const FlexibleLinkSpec& link, double v, const char* what) {
  if (!(v > 0.0) || !std::isfinite(v)) fail(link, std::string(what) + " " + fmt(v) + " must be positive and finite");
}

void validate(const FlexibleLinkSpec& link, int parent, int num_bodies) {
  if (parent < -1 || parent >= num_bodies)
    fail(link, "parent " + std::to_string(parent) + " is not a body of the tree (" + std::to_string(num_bodies) +
                   " bodies; -1 = the base)");
  positive(link, link.length, "length");
  if (link.segments < 1 || link.segments > kMaxFlexibleSegments)
    fail(link, "segments " + std::to_string(link.segments) + " must be 1.." + std::to_string(kMaxFlexibleSegments));
  const BeamSection& s = link.section;
  positive(link, s.density, "density");
  positive(link, s.area, "area");
  positive(link, s.youngs_modulus, "Young's modulus");
  positive(link, s.second_moment_y, "second moment I_y");
  positive(link, s.second_moment_z, "second moment I_z");
  if (link.torsion && !link.planar) {
    positive(link, s.shear_modulus, "shear modulus");
    positive(link, s.torsion_constant, "torsion constant");
  }
  positive(link, link.stiffness_factor, "stiffness factor");
  if (!(link.damping_time >= 0.0) || !std::isfinite(link.damping_time))
    fail(link, "damping time " + fmt(link.damping_time) + " s must be non-negative and finite");
  const TipPayload& p = link.payload;
  if (!(p.mass >= 0.0) || !std::isfinite(p.mass))
    fail(link, "payload mass " + fmt(p.mass) + " kg must be non-negative and finite");
  if (!p.com_offset.allFinite()) fail(link, "payload centre of mass is not finite");
  if (!p.inertia.allFinite()) fail(link, "payload inertia is not finite");
  const double scale = std::max(p.inertia.cwiseAbs().maxCoeff(), 1e-300);
  if ((p.inertia - p.inertia.transpose()).cwiseAbs().maxCoeff() > 1e-12 * scale)
    fail(link, "payload inertia is not symmetric");
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(p.inertia, Eigen::EigenvaluesOnly);
  if (eig.eigenvalues()[0] < -1e-12 * scale) fail(link, "payload inertia is not positive semi-definite");
}

// The slender prism of flexible_link.hpp about its centre, link axes, kg·m².
Mat3 segment_inertia(const BeamSection& s, double ls) {
  const double rho = s.density, axial = rho * s.area * ls * ls * ls / 12.0;
  return Vec3(rho * ls * (s.second_moment_y + s.second_moment_z), axial + rho * s.second_moment_y * ls,
              axial + rho * s.second_moment_z * ls)
      .asDiagonal();
}

// Body b with a rigid body of mass m, centre of mass c and inertia I (about c) welded on: the
// combined mass, centre of mass, and inertia about it by the parallel-axis theorem
// I = sum_k I_k + m_k (|d_k|² 1 - d_k d_k^T), d_k = c_k - c.
void merge_rigid(BodySpec& b, double m, const Vec3& c, const Mat3& I) {
  const double mt = b.mass + m;
  if (!(mt > 0.0)) return;
  const Vec3 ct = (b.mass * b.com + m * c) / mt;
  auto shift = [&](double mk, const Vec3& ck) {
    const Vec3 d = ck - ct;
    return Mat3(mk * (d.squaredNorm() * Mat3::Identity() - d * d.transpose()));
  };
  const Mat3 It = b.inertia + shift(b.mass, b.com) + I + shift(m, c);
  b.mass = mt;
  b.com = ct;
  b.inertia = 0.5 * (It + It.transpose());
}

}  // namespace

std::vector<double> flexible_link_segment_lengths(const FlexibleLinkSpec& link) {
  const int n = link.segments;
  if (n <= 1) return {link.length};
  const double cell = link.length / (n - 1);
  std::vector<double> ls(static_cast<std::size_t>(n), cell);
  ls.front() = ls.back() = 0.5 * cell;
  return ls;
}

Vec3 flexible_link_tip_point(const FlexibleLinkSpec& link) {
  return {flexible_link_segment_lengths(link).back(), 0.0, 0.0};
}

int append_flexible_link(TreeSpec& tree, int parent, const Vec3& position, const Mat3& rotation,
                         const FlexibleLinkSpec& link) {
  validate(link, parent, static_cast<int>(tree.bodies.size()));
  const BeamSection& s = link.section;
  const std::vector<double> ls = flexible_link_segment_lengths(link);
  const int n = link.segments;
  const double cell = n > 1 ? link.length / (n - 1) : link.length;
  // The cell's springs (flexible_link.hpp): k = kappa E I / l, k_x = kappa G J / l.
  const double kz = link.stiffness_factor * s.youngs_modulus * s.second_moment_z / cell;
  const double ky = link.stiffness_factor * s.youngs_modulus * s.second_moment_y / cell;
  const double kx = link.stiffness_factor * s.shear_modulus * s.torsion_constant / cell;
  struct CellJoint {
    Vec3 axis;
    double k;
    const char* tag;
  };
  std::vector<CellJoint> joints{{Vec3::UnitZ(), kz, "z"}};
  if (!link.planar) {
    joints.push_back({Vec3::UnitY(), ky, "y"});
    if (link.torsion) joints.push_back({Vec3::UnitX(), kx, "x"});
  }

  auto segment = [&](int j) {
    BodySpec b;
    b.name = link.name + ".seg" + std::to_string(j);
    b.mass = s.density * s.area * ls[j];
    b.com = {0.5 * ls[j], 0.0, 0.0};
    b.inertia = segment_inertia(s, ls[j]);
    return b;
  };

  BodySpec root = segment(0);
  if (!link.root_name.empty()) root.name = link.root_name;
  root.parent = parent;
  const FlexibleRootJoint& rj = link.root_joint;
  root.joint = rj.type;
  if (rj.type != JointType::kFixed) {
    root.axis = rj.axis;
    root.armature = rj.armature;
    root.stiffness = rj.stiffness;
    root.damping = rj.damping;
    root.spring_reference = rj.spring_reference;
  }
  root.position = position;
  root.rotation = rotation;
  tree.bodies.push_back(root);
  int last = static_cast<int>(tree.bodies.size()) - 1;

  for (int j = 1; j < n; ++j) {
    // The cell centre is the previous segment's far end; the joints there share that point.
    Vec3 at{ls[j - 1], 0.0, 0.0};
    for (std::size_t k = 0; k < joints.size(); ++k) {
      const bool carrier = k + 1 == joints.size();  // the segment itself carries the cell's last joint
      BodySpec b = carrier ? segment(j) : BodySpec{};
      if (!carrier) b.name = link.name + ".cell" + std::to_string(j) + "." + joints[k].tag;
      b.parent = last;
      b.joint = JointType::kRevolute;
      b.axis = joints[k].axis;
      b.position = at;
      b.stiffness = joints[k].k;
      b.damping = link.damping_time * joints[k].k;
      tree.bodies.push_back(b);
      last = static_cast<int>(tree.bodies.size()) - 1;
      at.setZero();
    }
  }

  const TipPayload& p = link.payload;
  if (p.mass > 0.0 || p.inertia.cwiseAbs().maxCoeff() > 0.0)
    merge_rigid(tree.bodies.back(), p.mass, flexible_link_tip_point(link) + p.com_offset, 0.5 * (p.inertia + p.inertia.transpose()));
  return last;
}

}  // namespace ff
