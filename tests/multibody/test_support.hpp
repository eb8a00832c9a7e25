// Shared helpers for the multibody tests: a seeded random source whose numbers are the same with
// every standard library, random bodies, trees and states, relative differences.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <sstream>
#include <string>

#include "multibody/algorithms.hpp"
#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff::test {

// SplitMix64 (Vigna): the same sequence everywhere (std::uniform_real_distribution is not).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int index(int n) { return static_cast<int>(uniform() * n); }  // 0 .. n-1
  Vec3 vec3(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  Vec3 unit() {
    for (;;) {
      const Vec3 v = vec3(-1.0, 1.0);
      const double n = v.norm();
      if (n > 0.1 && n <= 1.0) return v / n;
    }
  }
  Mat3 rotation() { return axis_angle(unit(), uniform(-std::numbers::pi, std::numbers::pi)); }
  SpatialMotion spatial(double lo, double hi) {
    SpatialMotion m;
    for (int k = 0; k < 6; ++k) m[k] = uniform(lo, hi);
    return m;
  }

 private:
  std::uint64_t s_;
};

// A solid box of mass m and sides a, b, c about its centre, its principal axes turned by R: kg·m².
inline Mat3 box_inertia(double m, double a, double b, double c, const Mat3& R = Mat3::Identity()) {
  const Vec3 p{m * (b * b + c * c) / 12.0, m * (a * a + c * c) / 12.0, m * (a * a + b * b) / 12.0};
  return R * p.asDiagonal() * R.transpose();
}

// A random body on parent `parent`: joint type drawn (revolute, prismatic, fixed with weights
// 0.55, 0.25, 0.2 unless `joint` is given), random unit axis, placement, mass 0.5..3 kg, centre of
// mass within 0.3 m, a box inertia (sides 0.05..0.6 m) turned by a random rotation, armature 0 or
// up to 0.2.
inline BodySpec random_body(Rng& rng, int parent, const JointType* joint = nullptr) {
  BodySpec b;
  b.parent = parent;
  if (joint) {
    b.joint = *joint;
  } else {
    const double u = rng.uniform();
    b.joint = u < 0.55 ? JointType::kRevolute : u < 0.8 ? JointType::kPrismatic : JointType::kFixed;
  }
  b.axis = rng.unit() * rng.uniform(0.5, 2.0);  // make_tree normalises it
  b.position = rng.vec3(-0.5, 0.5);
  b.rotation = rng.rotation();
  b.mass = rng.uniform(0.5, 3.0);
  b.com = rng.vec3(-0.3, 0.3);
  b.inertia = box_inertia(b.mass, rng.uniform(0.05, 0.6), rng.uniform(0.05, 0.6), rng.uniform(0.05, 0.6),
                          rng.rotation());
  b.armature = rng.uniform() < 0.5 ? 0.0 : rng.uniform(0.0, 0.2);
  return b;
}

// A random tree of n bodies: each body's parent drawn from the base and the bodies before it
// (chains, branches, stars), at least one moving joint; gravity 9.81 m/s² along a random direction
// half the time, else the default.
inline Tree random_tree(Rng& rng, int n) {
  TreeSpec spec;
  for (int i = 0; i < n; ++i) spec.bodies.push_back(random_body(rng, rng.index(i + 1) - 1));
  if (std::none_of(spec.bodies.begin(), spec.bodies.end(),
                   [](const BodySpec& b) { return b.joint != JointType::kFixed; }))
    spec.bodies.back().joint = JointType::kRevolute;
  if (rng.uniform() < 0.5) spec.gravity = 9.81 * rng.unit();
  return make_tree(spec);
}

// The spec a tree was made from (make_tree(spec_of(t)) rebuilds t), for tests that change a field.
inline TreeSpec spec_of(const Tree& tree) {
  TreeSpec spec;
  spec.gravity = tree.gravity();
  for (const Body& b : tree.bodies()) {
    BodySpec bs;
    bs.name = b.name;
    bs.parent = b.parent;
    bs.joint = b.joint;
    bs.axis = b.axis;
    bs.position = b.X_tree.position();
    bs.rotation = b.X_tree.rotation_matrix();
    bs.mass = b.mass;
    bs.com = b.com;
    bs.inertia = b.inertia_com;
    bs.armature = b.armature;
    bs.stiffness = b.stiffness;
    bs.damping = b.damping;
    bs.spring_reference = b.spring_reference;
    spec.bodies.push_back(bs);
  }
  return spec;
}

// A random joint position: angles in [-pi, pi] rad, slides in [-0.5, 0.5] m.
inline Eigen::VectorXd random_q(Rng& rng, const Tree& tree) {
  Eigen::VectorXd q(tree.nq());
  for (const Body& b : tree.bodies()) {
    if (b.dof < 0) continue;
    q[b.dof] = b.joint == JointType::kRevolute ? rng.uniform(-std::numbers::pi, std::numbers::pi)
                                               : rng.uniform(-0.5, 0.5);
  }
  return q;
}

inline Eigen::VectorXd random_vector(Rng& rng, int n, double lo, double hi) {
  Eigen::VectorXd v(n);
  for (int k = 0; k < n; ++k) v[k] = rng.uniform(lo, hi);
  return v;
}

// max |a - b| / max |b|: the difference relative to the reference's size.
inline double rel_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const double scale = b.cwiseAbs().maxCoeff();
  return (a - b).cwiseAbs().maxCoeff() / (scale > 0.0 ? scale : 1.0);
}

// A number for RecordProperty, in scientific notation (std::to_string's fixed six decimals hide 1e-13).
inline std::string sci(double v) {
  std::ostringstream o;
  o.precision(3);
  o << std::scientific << v;
  return o.str();
}

// One classical RK4 step on x = [q; qd], tau = the passive forces (nothing else applied).
struct Rk4 {
  const Tree& tree;
  TreeWorkspace ws;
  Eigen::VectorXd k[4], tmp, tau;
  explicit Rk4(const Tree& t) : tree(t), ws(t), tmp(2 * t.nv()), tau(t.nv()) {
    for (auto& ki : k) ki.resize(2 * t.nv());
  }
  void f(const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    const int n = tree.nv();
    dy.head(n) = y.tail(n);
    calc_passive_forces(tree, y.head(n), y.tail(n), tau);
    calc_forward_dynamics(tree, y.head(n), y.tail(n), tau, dy.tail(n), ws);
  }
  void step(Eigen::VectorXd& x, double h) {
    f(x, k[0]);
    tmp = x + 0.5 * h * k[0];
    f(tmp, k[1]);
    tmp = x + 0.5 * h * k[1];
    f(tmp, k[2]);
    tmp = x + h * k[2];
    f(tmp, k[3]);
    x += (h / 6.0) * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3]);
  }
};

}  // namespace ff::test
