// Tests of the robust notch filter of seed eq. 6 (kernel/notch.hpp): the continuous response,
// its Tustin-with-pre-warping cascade, the W-lane stepper and input validation.
#include "kernel/notch.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace {

using ff::Biquad;
using ff::NotchDesign;
using cd = std::complex<double>;

constexpr double kPi = std::numbers::pi;
constexpr double kT = 1e-3;  // 1 kHz controller

// The seed's typical design: notches at the two closed-loop resonances, alpha 1.6, critically damped poles.
NotchDesign seed_design(int order) {
  NotchDesign d;
  d.order = order;
  d.omega_z[0] = 2.0 * kPi * 0.274;
  d.omega_z[1] = 2.0 * kPi * 2.289;
  d.alpha[0] = d.alpha[1] = 1.6;
  d.zeta[0] = d.zeta[1] = 1.0;
  return d;
}

// Seed eq. 6 evaluated literally with s = j omega and complex powers, independent of the kernel's product form.
cd eq6_literal(const NotchDesign& d, double omega) {
  const cd s(0.0, omega);
  const double n = d.order;
  cd f(1.0, 0.0);
  for (int i = 0; i < 2; ++i) {
    const double wz = d.omega_z[i];
    const double wp = d.alpha[i] * wz;
    f *= std::pow((s / wz) * (s / wz) + 1.0, n);
    f /= std::pow((s / wp) * (s / wp) + 2.0 * d.zeta[i] * s / wp + 1.0, i == 0 ? n : n + 1.0);
  }
  return f;
}

// Continuous state-space realisation of eq. 6 as a series of second-order factors, each written as
// d + (beta1 s + beta0)/(s^2 + 2 zeta wp s + wp^2) in controllable form; independent of the Tustin code.
struct StateSpace {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C;
  double D = 1.0;
};

StateSpace eq6_state_space(const NotchDesign& d) {
  StateSpace sys;  // starts as the identity (no states, D = 1)
  sys.A.resize(0, 0);
  sys.B.resize(0);
  sys.C.resize(0);
  auto append = [&sys](double dd, double beta1, double beta0, double wp, double zeta) {
    const Eigen::Index m = sys.A.rows();
    // New states (x1, x2) of this factor: x1' = x2, x2' = -wp^2 x1 - 2 zeta wp x2 + u, u = C x + D u_in.
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m + 2, m + 2);
    A.topLeftCorner(m, m) = sys.A;
    A.block(m + 1, 0, 1, m) = sys.C;
    A(m, m + 1) = 1.0;
    A(m + 1, m) = -wp * wp;
    A(m + 1, m + 1) = -2.0 * zeta * wp;
    Eigen::VectorXd B = Eigen::VectorXd::Zero(m + 2);
    B.head(m) = sys.B;
    B(m + 1) = sys.D;
    // Output of this factor: beta0 x1 + beta1 x2 + dd u.
    Eigen::RowVectorXd C(m + 2);
    C.head(m) = dd * sys.C;
    C(m) = beta0;
    C(m + 1) = beta1;
    sys.A = A;
    sys.B = B;
    sys.C = C;
    sys.D = dd * sys.D;
  };
  for (int i = 0; i < 2; ++i) {
    const double wz = d.omega_z[i];
    const double wp = d.alpha[i] * wz;
    const double dd = (wp / wz) * (wp / wz);  // ((s/wz)^2 + 1)/((s/wp)^2 + ...) = dd + remainder
    for (int k = 0; k < d.order; ++k)
      append(dd, -2.0 * dd * d.zeta[i] * wp, dd * (wz * wz - wp * wp), wp, d.zeta[i]);
  }
  const double wp2 = d.alpha[1] * d.omega_z[1];
  append(0.0, 0.0, wp2 * wp2, wp2, d.zeta[1]);  // the extra pole pair of the second factor
  return sys;
}

// Continuous unit-step response sampled at t0, t0 + h, ..., by the exact matrix exponential of [A B; 0 0].
std::vector<double> continuous_step(const StateSpace& sys, double t0, double h, int count) {
  const Eigen::Index m = sys.A.rows();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(m + 1, m + 1);
  M.topLeftCorner(m, m) = sys.A;
  M.topRightCorner(m, 1) = sys.B;
  const Eigen::MatrixXd E0 = (M * t0).exp();
  const Eigen::MatrixXd E = (M * h).exp();
  Eigen::VectorXd z = Eigen::VectorXd::Zero(m + 1);
  z(m) = 1.0;
  z = E0 * z;
  std::vector<double> y(static_cast<std::size_t>(count));
  for (int k = 0; k < count; ++k) {
    y[static_cast<std::size_t>(k)] = sys.C.dot(z.head(m)) + sys.D;
    z = E * z;
  }
  return y;
}

// Runs one lane (W = 1) of a cascade from rest over the input sequence.
std::vector<double> run_alone(const std::vector<Biquad>& s, const std::vector<double>& in) {
  const int ns = static_cast<int>(s.size());
  std::vector<double> coef(5 * s.size()), state(2 * s.size(), 0.0), out(in.size());
  ff::pack_notch_sections(s, 1, 0, coef.data());
  for (std::size_t i = 0; i < in.size(); ++i) ff::step_notch(ns, 1, coef.data(), state.data(), &in[i], &out[i]);
  return out;
}

std::vector<double> log_grid(double lo, double hi, int points) {
  std::vector<double> w(static_cast<std::size_t>(points));
  for (int i = 0; i < points; ++i)
    w[static_cast<std::size_t>(i)] = lo * std::pow(hi / lo, static_cast<double>(i) / (points - 1));
  return w;
}

TEST(Notch, ContinuousResponseHasUnitDcGainAndZerosAtResonances) {
  for (int n = 1; n <= 3; ++n) {
    const NotchDesign d = seed_design(n);
    EXPECT_EQ(std::abs(ff::calc_notch_response(d, 0.0)), 1.0) << "n=" << n;
    EXPECT_LT(std::abs(ff::calc_notch_response(d, d.omega_z[0])), 1e-12) << "n=" << n;
    EXPECT_LT(std::abs(ff::calc_notch_response(d, d.omega_z[1])), 1e-12) << "n=" << n;
    // Product form agrees with the literal eq. 6 away from the zeros.
    for (double w : log_grid(1e-2, 1e4, 301)) {
      const cd lit = eq6_literal(d, w);
      EXPECT_LT(std::abs(ff::calc_notch_response(d, w) - lit), 1e-12 * std::max(std::abs(lit), 1e-3))
          << "n=" << n << " omega=" << w;
    }
    // Far above the poles |F| -> alpha1^(2n) alpha2^(2n) wp2^2 / omega^2 (relative degree 2).
    const double w = 1e5;
    const double wp2 = d.alpha[1] * d.omega_z[1];
    const double asym = std::pow(d.alpha[0] * d.alpha[1], 2.0 * n) * wp2 * wp2 / (w * w);
    EXPECT_NEAR(std::abs(ff::calc_notch_response(d, w)) / asym, 1.0, 1e-6) << "n=" << n;
  }
}

TEST(Notch, SectionsAreTwoNPlusOneWithUnitDcGainAndZerosOnUnitCircle) {
  for (int n = 1; n <= 3; ++n) {
    const NotchDesign d = seed_design(n);
    const std::vector<Biquad> s = ff::make_notch_sections(d, kT);
    ASSERT_EQ(s.size(), static_cast<std::size_t>(2 * n + 1));
    for (std::size_t k = 0; k < s.size(); ++k) {
      const Biquad& q = s[k];
      // DC gain (b0 + b1 + b2)/(1 + a1 + a2) of the stored coefficients.
      EXPECT_NEAR((q.b0 + q.b1 + q.b2) / ((1.0 + q.a1) + q.a2), 1.0, 1e-9) << "n=" << n << " k=" << k;
      // Stable poles: |a2| < 1 and |a1| < 1 + a2 (Jury).
      EXPECT_LT(std::abs(q.a2), 1.0);
      EXPECT_LT(std::abs(q.a1), 1.0 + q.a2);
      if (k < 2 * static_cast<std::size_t>(n)) {
        // Notch sections: symmetric numerator => zeros z, 1/z; on the unit circle at angle wz T.
        const double wz = d.omega_z[k < static_cast<std::size_t>(n) ? 0 : 1];
        EXPECT_EQ(q.b0, q.b2);
        EXPECT_NEAR(std::acos(-q.b1 / (2.0 * q.b0)) / (wz * kT), 1.0, 1e-9) << "n=" << n << " k=" << k;
      } else {
        // Low-pass section: double zero at z = -1.
        EXPECT_EQ(q.b1, 2.0 * q.b0);
        EXPECT_EQ(q.b2, q.b0);
      }
    }
  }
}

// Tustin with pre-warping maps z = exp(j w T) to s = j c_k tan(w T / 2), c_k = w_k / tan(w_k T / 2), per section.
// Each section's frequency is therefore off by c_k tan(wT/2)/w - 1 ~ ((wT)^2 - (w_k T)^2)/12; through the
// final low-pass roll-off (|dlnF/dln w| -> 2) that is ~(wT)^2/6: 2.6e-3 at 20 Hz, 1.6e-2 at 50 Hz. Below
// 2 Hz the constant offset (w_k T)^2/12 of the higher sections dominates, ~1e-4.
TEST(Notch, DiscreteCascadeMatchesContinuousResponse) {
  const double w_max = 2.0 * kPi * 50.0;
  for (int n = 1; n <= 3; ++n) {
    const NotchDesign d = seed_design(n);
    const std::vector<Biquad> s = ff::make_notch_sections(d, kT);
    double e2 = 0.0, e20 = 0.0, e50 = 0.0, worst_vs_model = 0.0;
    for (double w : log_grid(0.01, w_max, 2001)) {
      const cd fc = ff::calc_notch_response(d, w);
      const cd fd = ff::calc_sections_response(s, w, kT);
      const double e = std::abs(fd - fc) / std::max(std::abs(fc), 1e-3);
      if (w <= 2.0 * kPi * 2.0) e2 = std::max(e2, e);
      if (w <= 2.0 * kPi * 20.0) e20 = std::max(e20, e);
      e50 = std::max(e50, e);
      const double model = (w * kT) * (w * kT) / 6.0;
      if (w >= 2.0 * kPi * 10.0) worst_vs_model = std::max(worst_vs_model, e / model);
    }
    std::printf("n=%d max rel err: <=2 Hz %.3e, <=20 Hz %.3e, <=50 Hz %.3e, err/((wT)^2/6) above 10 Hz %.3f\n", n,
                e2, e20, e50, worst_vs_model);
    EXPECT_LT(e2, 2e-4) << "n=" << n;
    EXPECT_LT(e20, 4e-3) << "n=" << n;
    EXPECT_LT(e50, 2e-2) << "n=" << n;
    EXPECT_LT(worst_vs_model, 1.5) << "n=" << n;  // the error is Tustin's second-order frequency warping
    // Discrete zeros exactly at the pre-warped frequencies.
    EXPECT_LT(std::abs(ff::calc_sections_response(s, d.omega_z[0], kT)), 1e-9) << "n=" << n;
    EXPECT_LT(std::abs(ff::calc_sections_response(s, d.omega_z[1], kT)), 1e-9) << "n=" << n;
    EXPECT_NEAR(std::abs(ff::calc_sections_response(s, 0.0, kT)), 1.0, 1e-9) << "n=" << n;
  }
}

// Tustin is the trapezoidal rule, which treats the sampled step as a ramp over the first sample: the
// discrete sample k matches the continuous step response at t = (k + 1/2) T up to O(T^2) terms. Eq. 6 has
// relative degree 2 with y''(0+) = G = (alpha1 alpha2)^(2n) wp2^2, and the worst sample is the first one,
// y_d[0] ~ G T^2/4 against y_c(T/2) ~ G T^2/8: so max |y_d - y_c| <= G T^2 / 8 (measured 0.80-0.92 of it).
// After the first second the error is the O(T^2) warping of the slow modes only.
TEST(Notch, StepResponseSettlesToInputWithoutOvershootBeyondBound) {
  const int samples = 30000;  // 30 s at 1 kHz
  const double late_bound[3] = {1e-5, 3e-5, 8e-5};  // max |y_d - y_c| for t > 1 s, measured 4.1e-6, 1.6e-5, 4.0e-5
  for (int n = 1; n <= 3; ++n) {
    const NotchDesign d = seed_design(n);
    const std::vector<double> yd = run_alone(ff::make_notch_sections(d, kT), std::vector<double>(samples, 1.0));
    const std::vector<double> yc = continuous_step(eq6_state_space(d), 0.5 * kT, kT, samples);
    EXPECT_NEAR(yd.back(), 1.0, 1e-9) << "n=" << n;
    EXPECT_NEAR(yc.back(), 1.0, 1e-9) << "n=" << n;
    const double wp2 = d.alpha[1] * d.omega_z[1];
    const double bound = std::pow(d.alpha[0] * d.alpha[1], 2.0 * n) * wp2 * wp2 * kT * kT / 8.0;
    double err = 0.0, err_late = 0.0, peak_d = 0.0, peak_c = 0.0, under_d = 0.0, under_c = 0.0;
    for (int k = 0; k < samples; ++k) {
      const std::size_t i = static_cast<std::size_t>(k);
      const double e = std::abs(yd[i] - yc[i]);
      err = std::max(err, e);
      if (k > 1000) err_late = std::max(err_late, e);
      peak_d = std::max(peak_d, yd[i]);
      peak_c = std::max(peak_c, yc[i]);
      under_d = std::min(under_d, yd[i]);
      under_c = std::min(under_c, yc[i]);
    }
    std::printf("n=%d step: end-1 %.3e, max|yd-yc| %.3e (G T^2/8 = %.3e), after 1 s %.3e, peak d %.6f c %.6f, "
                "min d %.6f c %.6f\n", n, yd.back() - 1.0, err, bound, err_late, peak_d, peak_c, under_d, under_c);
    EXPECT_LT(err, bound) << "n=" << n;
    EXPECT_LT(err_late, late_bound[n - 1]) << "n=" << n;
    EXPECT_LT(peak_d, peak_c + bound) << "n=" << n;
    EXPECT_GT(under_d, under_c - bound) << "n=" << n;
    if (n == 1) {
      // The first-order filter's step response is monotone in both worlds: no overshoot at all.
      EXPECT_LT(peak_c, 1.0 + 1e-12);
      EXPECT_LT(peak_d, 1.0 + 1e-9);
      EXPECT_GE(under_d, 0.0);
    }
  }
}

// Lanes of one block share nothing: W filters with different designs and inputs, stepped together,
// reproduce bit for bit the same filters stepped alone with W = 1 (also in place, in == out).
TEST(Notch, LanesAreIndependentAndBitIdentical) {
  const int n = 2;
  const int samples = 5000;
  for (int W : {4, 7}) {
    std::vector<std::vector<Biquad>> designs;
    std::vector<std::vector<double>> inputs;
    for (int l = 0; l < W; ++l) {
      NotchDesign d = seed_design(n);
      d.omega_z[0] *= 1.0 + 0.13 * l;
      d.omega_z[1] *= 1.0 + 0.07 * l;
      d.alpha[0] = 1.2 + 0.1 * l;
      d.alpha[1] = 1.9 - 0.1 * l;
      d.zeta[0] = 0.5 + 0.2 * l;
      d.zeta[1] = 1.0 + 0.05 * l;
      designs.push_back(ff::make_notch_sections(d, kT));
      std::vector<double> in(samples);
      for (int k = 0; k < samples; ++k) {
        const double u = std::min(1.0, k * kT / (1.0 + 0.3 * l));  // cubic move of seed length, then hold
        in[static_cast<std::size_t>(k)] = (l + 1) * (3.0 * u * u - 2.0 * u * u * u) + 0.01 * std::sin(0.37 * k + l);
      }
      inputs.push_back(in);
    }
    const int ns = 2 * n + 1;
    std::vector<double> coef(static_cast<std::size_t>(5 * ns * W)), state(static_cast<std::size_t>(2 * ns * W), 0.0);
    for (int l = 0; l < W; ++l) ff::pack_notch_sections(designs[static_cast<std::size_t>(l)], W, l, coef.data());
    std::vector<std::vector<double>> together(static_cast<std::size_t>(W), std::vector<double>(samples));
    std::vector<double> buf(static_cast<std::size_t>(W));
    for (int k = 0; k < samples; ++k) {
      for (int l = 0; l < W; ++l) buf[static_cast<std::size_t>(l)] = inputs[static_cast<std::size_t>(l)][static_cast<std::size_t>(k)];
      ff::step_notch(ns, W, coef.data(), state.data(), buf.data(), buf.data());
      for (int l = 0; l < W; ++l) together[static_cast<std::size_t>(l)][static_cast<std::size_t>(k)] = buf[static_cast<std::size_t>(l)];
    }
    for (int l = 0; l < W; ++l) {
      const std::size_t i = static_cast<std::size_t>(l);
      const std::vector<double> alone = run_alone(designs[i], inputs[i]);
      int mismatches = 0;
      for (int k = 0; k < samples; ++k) {
        const std::size_t j = static_cast<std::size_t>(k);
        if (std::memcmp(&alone[j], &together[i][j], sizeof(double)) != 0) ++mismatches;
      }
      EXPECT_EQ(mismatches, 0) << "W=" << W << " lane=" << l;
      EXPECT_NE(alone.back(), 0.0);
    }
  }
}

// reset_notch_state puts one lane at rest at x0: feeding x0 keeps the output at x0 (to rounding of the
// recursion, |dy| <= 1e-9 |x0|; measured 3e-10 at x0 = 3.7, n = 3) and leaves the other lanes untouched.
TEST(Notch, ResetStateHoldsConstantInput) {
  const int W = 3;
  for (int n = 1; n <= 3; ++n) {
    const std::vector<Biquad> s = ff::make_notch_sections(seed_design(n), kT);
    const int ns = static_cast<int>(s.size());
    std::vector<double> coef(static_cast<std::size_t>(5 * ns * W)), state(static_cast<std::size_t>(2 * ns * W), 0.0);
    for (int l = 0; l < W; ++l) ff::pack_notch_sections(s, W, l, coef.data());
    const double x0 = 3.7;
    ff::reset_notch_state(ns, W, 1, coef.data(), x0, state.data());
    for (int k = 0; k < ns; ++k) {  // lanes 0 and 2 still at rest
      for (int j = 0; j < 2; ++j) {
        EXPECT_EQ(state[static_cast<std::size_t>((2 * k + j) * W + 0)], 0.0);
        EXPECT_EQ(state[static_cast<std::size_t>((2 * k + j) * W + 2)], 0.0);
      }
    }
    const double in[W] = {0.0, x0, 0.0};
    double out[W];
    double dev = 0.0;
    for (int k = 0; k < 60000; ++k) {  // 60 s
      ff::step_notch(ns, W, coef.data(), state.data(), in, out);
      dev = std::max(dev, std::abs(out[1] - x0));
      ASSERT_EQ(out[0], 0.0);
      ASSERT_EQ(out[2], 0.0);
    }
    std::printf("n=%d hold at %.1f: max |y - x0| = %.3e\n", n, x0, dev);
    EXPECT_LT(dev, 1e-9 * x0) << "n=" << n;
  }
}

TEST(Notch, RejectsOrderBelowOne) {
  NotchDesign d = seed_design(1);
  d.order = 0;
  EXPECT_THROW(ff::make_notch_sections(d, kT), std::invalid_argument);
  EXPECT_THROW(ff::calc_notch_response(d, 1.0), std::invalid_argument);
}

TEST(Notch, RejectsNonPositiveOrNonFiniteFrequencies) {
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    for (int i = 0; i < 2; ++i) {
      NotchDesign d = seed_design(1);
      d.omega_z[i] = bad;
      EXPECT_THROW(ff::make_notch_sections(d, kT), std::invalid_argument) << bad;
      EXPECT_THROW(ff::calc_notch_response(d, 1.0), std::invalid_argument) << bad;
    }
  }
}

TEST(Notch, RejectsNonPositiveAlphaAndZeta) {
  for (double bad : {0.0, -1.6}) {
    for (int i = 0; i < 2; ++i) {
      NotchDesign d = seed_design(1);
      d.alpha[i] = bad;
      EXPECT_THROW(ff::make_notch_sections(d, kT), std::invalid_argument);
      d = seed_design(1);
      d.zeta[i] = bad;
      EXPECT_THROW(ff::make_notch_sections(d, kT), std::invalid_argument);
      EXPECT_THROW(ff::calc_notch_response(d, 1.0), std::invalid_argument);
    }
  }
}

// Zeros and poles must stay below omega T = pi/2 (a quarter of the sample rate).
TEST(Notch, RejectsFrequenciesTooCloseToNyquist) {
  NotchDesign d = seed_design(1);
  d.omega_z[1] = 2.0 * kPi * 300.0;  // omega_z T = 1.88
  EXPECT_THROW(ff::make_notch_sections(d, kT), std::invalid_argument);
  d.omega_z[1] = 2.0 * kPi * 200.0;  // omega_z T = 1.26 passes, but omega_p T = 2.01 does not
  EXPECT_THROW(ff::make_notch_sections(d, kT), std::invalid_argument);
  d.alpha[1] = 1.2;                  // omega_p T = 1.51: accepted
  EXPECT_NO_THROW(ff::make_notch_sections(d, kT));
}

TEST(Notch, RejectsBadPeriodAndLane) {
  const NotchDesign d = seed_design(1);
  EXPECT_THROW(ff::make_notch_sections(d, 0.0), std::invalid_argument);
  EXPECT_THROW(ff::make_notch_sections(d, -kT), std::invalid_argument);
  EXPECT_THROW(ff::calc_sections_response({}, 1.0, 0.0), std::invalid_argument);
  const std::vector<Biquad> s = ff::make_notch_sections(d, kT);
  std::vector<double> coef(5 * s.size() * 2), state(2 * s.size() * 2);
  EXPECT_THROW(ff::pack_notch_sections(s, 2, 2, coef.data()), std::invalid_argument);
  EXPECT_THROW(ff::pack_notch_sections(s, 0, 0, coef.data()), std::invalid_argument);
  EXPECT_THROW(ff::reset_notch_state(3, 2, -1, coef.data(), 0.0, state.data()), std::invalid_argument);
}

}  // namespace
