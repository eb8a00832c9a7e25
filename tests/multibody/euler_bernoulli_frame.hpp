// An independent oracle for the lumped flexible links (multibody/flexible_link.hpp): the exact natural
// frequencies of a planar two-link arm of two continuous Euler–Bernoulli beams, both arm joints
// locked, found as the roots of the frequency determinant of the boundary-value problem. Test code
// only; it shares nothing with the library but Eigen.
//
// The arm, in the xy plane, bending in the plane:
//   link 1  x1 in [0, L1] along +x, flexural rigidity EI1, mass per length rho A1, clamped at the base
//           (the shoulder locked); transverse deflection W1(x1) along +y;
//   link 2  x2 in [0, L2] along e2 = (cos phi, sin phi) from link 1's tip, rigidly joined to it at the
//           elbow angle phi (the elbow locked); EI2, rho A2; transverse deflection W2(x2) along
//           n2 = (-sin phi, cos phi);
//   payload an optional rigid body at link 2's tip: mass m_p (its centre of mass at the tip point) and
//           rotary inertia J_p about it (about z).
// Both links are inextensible (the lumped links are too: rigid segments and revolute joints). Link 1
// is clamped, so its tip has no axial motion: the elbow moves by W1(L1) along y only. Link 2 then
// moves along its axis rigidly by U2 = W1(L1) (y . e2) = W1(L1) sin phi, and its root deflection is
// W2(0) = W1(L1) (y . n2) = W1(L1) cos phi. At phi = 90 deg link 2 slides along its own axis with the
// elbow's deflection and its whole mass rho A2 L2 + m_p loads link 1's tip transversely.
//
// Equations (Euler–Bernoulli beam theory, e.g. S. S. Rao, Vibration of Continuous Systems, 2nd ed.,
// 2019, ch. 11, the beam's equation and its boundary conditions; the frame's joint conditions written
// from Hamilton's principle): harmonic motion at omega, per link
//   EI W'''' = rho A omega^2 W,  beta^4 = rho A omega^2 / EI,
//   W(x) = c1 sin(beta x) + c2 cos(beta x) + c3 exp(-beta x) + c4 exp(-beta (L - x))
// (the hyperbolic pair as decaying exponentials, so no entry grows as exp(beta L): the same space as
// sinh, cosh, and the determinant stays well scaled at high beta L). Stationarity of
//   Pi = 1/2 sum_i int EI_i W_i''^2 - omega^2/2 [ sum_i int rho A_i W_i^2 + (rho A2 L2 + m_p) U2^2
//        + m_p W2(L2)^2 + J_p W2'(L2)^2 ]
// under the constraints W1(0) = W1'(0) = 0, W2(0) = cos phi W1(L1), W2'(0) = W1'(L1) (the rigid
// elbow: one rotation), U2 = sin phi W1(L1), integrating by parts, gives the field equations and,
// from the free variations delta W1'(L1), delta W1(L1), delta W2'(L2), delta W2(L2):
//   (1) W1(0) = 0                                       clamped base
//   (2) W1'(0) = 0
//   (3) W2(0) - cos phi W1(L1) = 0                      elbow: displacement continuity
//   (4) W2'(0) - W1'(L1) = 0                            elbow: slope continuity (rigid joint)
//   (5) EI1 W1''(L1) - EI2 W2''(0) = 0                  elbow: moment balance
//   (6) -EI1 W1'''(L1) + cos phi EI2 W2'''(0)           elbow: force balance along y (link 1's axial
//       - omega^2 (rho A2 L2 + m_p) sin^2 phi W1(L1) = 0   force takes the x balance), link 2's shear
//                                                       and its rigid axial inertia
//   (7) EI2 W2''(L2) - omega^2 J_p W2'(L2) = 0          tip: moment balance with the payload's J_p
//   (8) -EI2 W2'''(L2) - omega^2 m_p W2(L2) = 0         tip: shear balance with the payload's m_p
// With phi = 0 these are the transfer conditions of one beam through a section; with a single link
// (7) and (8) are the classical tip-body conditions whose determinant is
// cantilever_tip_body_equation below (with the tip mass alone: Laura, Pombo & Susemihl, J. Sound
// Vib. 37, 1974; Blevins, Formulas for Natural Frequency and Mode Shape, 1979, ch. 8).
// Each row is divided by its natural scale (EI1 beta1^k for a k-th derivative, W2's derivatives as
// multiples of W2^(k)/beta2^k), so every entry is O(1) times a mass or stiffness ratio, and the 8 x 8
// determinant D(omega) is a smooth real function whose simple zeros are the natural frequencies. They
// are bracketed by D's sign changes on a fine grid in lambda = beta1 L1 and refined by bisection.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <vector>

namespace ff::test {

struct EbLink {
  double length = 0.0;             // L, m
  double flexural_rigidity = 0.0;  // EI, N·m²
  double mass_per_length = 0.0;    // rho A, kg/m
};

struct EbTwoLinkArm {
  EbLink link1, link2;
  double elbow_angle = 0.0;  // phi, rad: link 2's axis turned from link 1's about z
  double tip_mass = 0.0;     // m_p, kg, at link 2's tip point
  double tip_inertia = 0.0;  // J_p, kg·m², the payload's rotary inertia about z through the tip point
};

// beta for a link at omega: (rho A omega^2 / EI)^(1/4), 1/m.
inline double eb_beta(const EbLink& link, double omega) {
  return std::sqrt(omega * std::sqrt(link.mass_per_length / link.flexural_rigidity));
}

// The k-th derivative of the four basis functions at x, divided by beta^k (k = 0..3):
// sin(beta x), cos(beta x), exp(-beta x), exp(-beta (L - x)).
inline Eigen::RowVector4d eb_basis(double beta, double L, double x, int k) {
  const double s = std::sin(beta * x), c = std::cos(beta * x);
  const double e1 = std::exp(-beta * x), e2 = std::exp(-beta * (L - x));
  switch (k) {
    case 0: return {s, c, e1, e2};
    case 1: return {c, -s, -e1, e2};
    case 2: return {-s, -c, e1, e2};
    case 3: return {-c, s, -e1, e2};
    default: throw std::invalid_argument("eb_basis: derivative order 0..3");
  }
}

// The scaled 8 x 8 matrix of equations (1)-(8) above at omega > 0; unknowns [c1..c4 of link 1,
// c1..c4 of link 2].
inline Eigen::Matrix<double, 8, 8> two_link_frequency_matrix(const EbTwoLinkArm& arm, double omega) {
  const EbLink &a = arm.link1, &b = arm.link2;
  const double b1 = eb_beta(a, omega), b2 = eb_beta(b, omega);
  const double L1 = a.length, L2 = b.length;
  const double r = b2 / b1, s = b.flexural_rigidity / a.flexural_rigidity;
  const double cphi = std::cos(arm.elbow_angle), sphi = std::sin(arm.elbow_angle);
  const double link2_mass = b.mass_per_length * L2 + arm.tip_mass;
  auto B1 = [&](double x, int k) { return eb_basis(b1, L1, x, k); };
  auto B2 = [&](double x, int k) { return eb_basis(b2, L2, x, k); };
  Eigen::Matrix<double, 8, 8> D = Eigen::Matrix<double, 8, 8>::Zero();
  // (1), (2): W1(0) = 0, W1'(0)/beta1 = 0.
  D.block<1, 4>(0, 0) = B1(0.0, 0);
  D.block<1, 4>(1, 0) = B1(0.0, 1);
  // (3): W2(0) - cos phi W1(L1) = 0.
  D.block<1, 4>(2, 0) = -cphi * B1(L1, 0);
  D.block<1, 4>(2, 4) = B2(0.0, 0);
  // (4): (W2'(0) - W1'(L1)) / beta1 = 0.
  D.block<1, 4>(3, 0) = -B1(L1, 1);
  D.block<1, 4>(3, 4) = r * B2(0.0, 1);
  // (5): (EI1 W1''(L1) - EI2 W2''(0)) / (EI1 beta1^2) = 0.
  D.block<1, 4>(4, 0) = B1(L1, 2);
  D.block<1, 4>(4, 4) = -s * r * r * B2(0.0, 2);
  // (6) / (EI1 beta1^3), with omega^2 / (EI1 beta1^3) = beta1 / (rho A1).
  D.block<1, 4>(5, 0) = -B1(L1, 3) - (b1 * link2_mass * sphi * sphi / a.mass_per_length) * B1(L1, 0);
  D.block<1, 4>(5, 4) = cphi * s * r * r * r * B2(0.0, 3);
  // (7) / (EI2 beta2^2), with omega^2 / (EI2 beta2) = beta2^3 / (rho A2).
  D.block<1, 4>(6, 4) = B2(L2, 2) - (b2 * b2 * b2 * arm.tip_inertia / b.mass_per_length) * B2(L2, 1);
  // (8) / (EI2 beta2^3), with omega^2 / (EI2 beta2^3) = beta2 / (rho A2).
  D.block<1, 4>(7, 4) = -B2(L2, 3) - (b2 * arm.tip_mass / b.mass_per_length) * B2(L2, 0);
  return D;
}

inline double two_link_frequency_determinant(const EbTwoLinkArm& arm, double omega) {
  return two_link_frequency_matrix(arm, omega).fullPivLu().determinant();
}

// The first `count` zeros of f on (lo, hi], bracketed by sign changes on the grid lo + k h and refined
// by bisection to the last bit. Throws if fewer are found.
inline std::vector<double> scan_roots(const std::function<double(double)>& f, double lo, double hi, double h,
                                      int count) {
  std::vector<double> roots;
  double x0 = lo, f0 = f(x0);
  for (long k = 1; static_cast<int>(roots.size()) < count; ++k) {
    const double x1 = lo + static_cast<double>(k) * h;
    if (x1 > hi) throw std::runtime_error("scan_roots: fewer roots than asked for below the scan's end");
    const double f1 = f(x1);
    if (f1 == 0.0) {
      roots.push_back(x1);
    } else if ((f0 < 0.0) != (f1 < 0.0) && f0 != 0.0) {
      double a = x0, b = x1, fa = f0;
      for (int it = 0; it < 200 && b - a > 4.0 * std::numeric_limits<double>::epsilon() * b; ++it) {
        const double m = 0.5 * (a + b), fm = f(m);
        if (fm == 0.0) a = b = m;
        else if ((fm < 0.0) == (fa < 0.0)) a = m, fa = fm;
        else b = m;
      }
      roots.push_back(0.5 * (a + b));
    }
    x0 = x1;
    f0 = f1;
  }
  return roots;
}

// The first `count` natural frequencies of the arm, rad/s, ascending: D's zeros in lambda = beta1 L1
// on a grid of step 1e-3 (the modes of a two-link arm are ~1 apart in lambda or more), omega =
// lambda^2 sqrt(EI1 / (rho A1 L1^4)).
inline std::vector<double> two_link_natural_frequencies(const EbTwoLinkArm& arm, int count) {
  const EbLink& a = arm.link1;
  const double scale = std::sqrt(a.flexural_rigidity / (a.mass_per_length * std::pow(a.length, 4)));
  const auto f = [&](double lambda) { return two_link_frequency_determinant(arm, lambda * lambda * scale); };
  std::vector<double> omega = scan_roots(f, 1e-3, 200.0, 1e-3, count);
  for (double& w : omega) w = w * w * scale;
  return omega;
}

// The frequency equation of a uniform cantilever carrying a tip body, lambda = beta L, mass ratio
// mu = m_p / (rho A L), inertia ratio j = J_p / (rho A L^3): the 4 x 4 determinant of the clamped-free
// beam in sin, cos, sinh, cosh with the tip conditions (7), (8), expanded (with j = 0 it is the
// classical tip-mass equation of Laura, Pombo & Susemihl 1974 and Blevins 1979, ch. 8):
//   1 + cos cosh + lambda mu (cos sinh - sin cosh) - lambda^3 j (sin cosh + cos sinh)
//     + lambda^4 mu j (1 - cos cosh) = 0,
// divided by cosh lambda to keep it bounded.
inline double cantilever_tip_body_equation(double lambda, double mu, double j) {
  const double s = std::sin(lambda), c = std::cos(lambda);
  const double t = std::tanh(lambda), sech = 1.0 / std::cosh(lambda);
  return sech + c + lambda * mu * (c * t - s) - lambda * lambda * lambda * j * (s + c * t) +
         std::pow(lambda, 4) * mu * j * (sech - c);
}

// Its first `count` roots lambda_n = beta_n L.
inline std::vector<double> cantilever_tip_body_roots(double mu, double j, int count) {
  return scan_roots([&](double l) { return cantilever_tip_body_equation(l, mu, j); }, 1e-3, 200.0, 1e-3, count);
}

}  // namespace ff::test
