// Robust notch filter of seed eq. 6: continuous response, Tustin-with-pre-warping sections and the
// W-lane transposed-direct-form-II stepper (see notch.hpp).
#include "kernel/notch.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace ff {

namespace {

// Largest omega * period accepted for a zero or pole: a quarter of the sample rate (half Nyquist).
constexpr double kMaxOmegaPeriod = 0.5 * std::numbers::pi;

// Reject designs eq. 6 is not defined for (seed eq. 6 needs n >= 1, omega_z > 0, alpha > 0, zeta > 0).
void check_design(const NotchDesign& d) {
  if (d.order < 1) throw std::invalid_argument("notch: order must be >= 1");
  for (int i = 0; i < 2; ++i) {
    if (!(d.omega_z[i] > 0.0) || !std::isfinite(d.omega_z[i]))
      throw std::invalid_argument("notch: omega_z must be positive and finite");
    if (!(d.alpha[i] > 0.0) || !std::isfinite(d.alpha[i]))
      throw std::invalid_argument("notch: alpha must be positive and finite");
    if (!(d.zeta[i] > 0.0) || !std::isfinite(d.zeta[i]))
      throw std::invalid_argument("notch: zeta must be positive and finite");
  }
}

// Reject a sample period that is not positive and finite.
void check_period(double period) {
  if (!(period > 0.0) || !std::isfinite(period))
    throw std::invalid_argument("notch: period must be positive and finite");
}

// Reject a lane layout that does not hold lane `lane`.
void check_lanes(int nsections, int W, int lane) {
  if (nsections < 0) throw std::invalid_argument("notch: nsections must be >= 0");
  if (W < 1) throw std::invalid_argument("notch: W must be >= 1");
  if (lane < 0 || lane >= W) throw std::invalid_argument("notch: lane out of range");
}

// Tustin map s = c (1 - z^-1)/(1 + z^-1) with c pre-warped so that s = j w0 at z = exp(j w0 T)
// (Franklin, Powell & Workman, Digital Control, Tustin with pre-warping).
double prewarp_gain(double w0, double period) { return w0 / std::tan(0.5 * w0 * period); }

// Denominator (s/wp)^2 + 2 zeta s/wp + 1 under Tustin, normalised to a0 = 1; also returns the
// DC value 1 + a1 + a2, formed so that it is the exact sum of the stored a1, a2 whenever they cancel.
struct Den { double d0, a1, a2, dc; };  // d0: the a0 the others were divided by
Den tustin_den(double c, double wp, double zeta) {
  const double B = (c / wp) * (c / wp);
  const double C = 2.0 * zeta * c / wp;
  const double d0 = B + C + 1.0;
  Den den;
  den.d0 = d0;
  den.a1 = (2.0 - 2.0 * B) / d0;
  den.a2 = (B - C + 1.0) / d0;
  den.dc = (1.0 + den.a1) + den.a2;
  return den;
}

// One notch section of seed eq. 6, ((s/wz)^2 + 1)/((s/wp)^2 + 2 zeta s/wp + 1), pre-warped at wz.
// Numerator under Tustin: (A+1) + (2-2A) z^-1 + (A+1) z^-2, A = (c/wz)^2; b1 is taken from
// b0 + b1 + b2 = 1 + a1 + a2 so that the stored coefficients have DC gain 1 to the last bit of b1.
Biquad notch_section(double wz, double wp, double zeta, double period) {
  const double c = prewarp_gain(wz, period);
  const Den den = tustin_den(c, wp, zeta);
  const double A = (c / wz) * (c / wz);
  const double b0 = (A + 1.0) / den.d0;
  return Biquad{b0, den.dc - 2.0 * b0, b0, den.a1, den.a2};
}

// The extra low-pass factor 1/((s/wp)^2 + 2 zeta s/wp + 1) of seed eq. 6, pre-warped at wp.
// Numerator under Tustin: (1 + z^-1)^2 scaled to DC gain 1, exactly: b = (1 + a1 + a2) [1/4, 1/2, 1/4].
Biquad lowpass_section(double wp, double zeta, double period) {
  const double c = prewarp_gain(wp, period);
  const Den den = tustin_den(c, wp, zeta);
  return Biquad{0.25 * den.dc, 0.5 * den.dc, 0.25 * den.dc, den.a1, den.a2};
}

}  // namespace

// F(j omega) of seed eq. 6 as the product of its factors, each formed from real parts so that
// (j omega/wz)^2 + 1 = 1 - (omega/wz)^2 is exactly 0 at omega = wz.
std::complex<double> calc_notch_response(const NotchDesign& d, double omega) {
  check_design(d);
  std::complex<double> f(1.0, 0.0);
  for (int i = 0; i < 2; ++i) {
    const double rz = omega / d.omega_z[i];
    const double rp = omega / (d.alpha[i] * d.omega_z[i]);
    const std::complex<double> num(1.0 - rz * rz, 0.0);
    const std::complex<double> den(1.0 - rp * rp, 2.0 * d.zeta[i] * rp);
    const std::complex<double> q = num / den;
    for (int k = 0; k < d.order; ++k) f *= q;
    if (i == 1) f /= den;  // the extra pole pair: exponent n + 1 on the second denominator
  }
  return f;
}

// Seed eq. 6 split into 2n+1 unit-DC-gain sections: n x (wz1/wp1), n x (wz2/wp2), 1 x (1/wp2).
std::vector<Biquad> make_notch_sections(const NotchDesign& d, double period) {
  check_design(d);
  check_period(period);
  const double wp[2] = {d.alpha[0] * d.omega_z[0], d.alpha[1] * d.omega_z[1]};
  for (int i = 0; i < 2; ++i) {
    if (d.omega_z[i] * period > kMaxOmegaPeriod || wp[i] * period > kMaxOmegaPeriod)
      throw std::invalid_argument("notch: omega * period too close to Nyquist (limit pi/2)");
  }
  std::vector<Biquad> s;
  s.reserve(2 * static_cast<std::size_t>(d.order) + 1);
  for (int i = 0; i < 2; ++i) {
    const Biquad q = notch_section(d.omega_z[i], wp[i], d.zeta[i], period);
    for (int k = 0; k < d.order; ++k) s.push_back(q);
  }
  s.push_back(lowpass_section(wp[1], d.zeta[1], period));
  return s;
}

// Product over sections of B(z)/A(z) at z^-1 = exp(-j omega T).
std::complex<double> calc_sections_response(const std::vector<Biquad>& s, double omega, double period) {
  check_period(period);
  const std::complex<double> zi = std::polar(1.0, -omega * period);
  const std::complex<double> zi2 = zi * zi;
  std::complex<double> f(1.0, 0.0);
  for (const Biquad& q : s) {
    const std::complex<double> num = q.b0 + q.b1 * zi + q.b2 * zi2;
    const std::complex<double> den = 1.0 + q.a1 * zi + q.a2 * zi2;
    f *= num / den;
  }
  return f;
}

// One sample through every section for every lane, transposed direct form II:
// y = b0 x + s0, s0 <- b1 x - a1 y + s1, s1 <- b2 x - a2 y. out doubles as the inter-section buffer.
void step_notch(int nsections, int W, const double* coef, double* state, const double* in, double* out) {
  const double* x = in;
  for (int k = 0; k < nsections; ++k) {
    const double* b0 = coef + (5 * k + 0) * W;
    const double* b1 = coef + (5 * k + 1) * W;
    const double* b2 = coef + (5 * k + 2) * W;
    const double* a1 = coef + (5 * k + 3) * W;
    const double* a2 = coef + (5 * k + 4) * W;
    double* s0 = state + (2 * k + 0) * W;
    double* s1 = state + (2 * k + 1) * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double xl = x[l];
      const double yl = b0[l] * xl + s0[l];
      s0[l] = b1[l] * xl - a1[l] * yl + s1[l];
      s1[l] = b2[l] * xl - a2[l] * yl;
      out[l] = yl;
    }
    x = out;
  }
  // No sections: the filter is the identity.
  if (nsections == 0 && out != in) {
    for (int l = 0; l < W; ++l) out[l] = in[l];
  }
}

// Scatter the sections' coefficients into lane `lane` of the structure-of-arrays block.
void pack_notch_sections(const std::vector<Biquad>& s, int W, int lane, double* coef) {
  const int n = static_cast<int>(s.size());
  check_lanes(n, W, lane);
  for (int k = 0; k < n; ++k) {
    const Biquad& q = s[static_cast<std::size_t>(k)];
    const double c[5] = {q.b0, q.b1, q.b2, q.a1, q.a2};
    for (int j = 0; j < 5; ++j) coef[(5 * k + j) * W + lane] = c[j];
  }
}

// Steady state of transposed direct form II at input = output = x0 for every section:
// s0 = x0 - b0 x0 (from y = b0 x + s0), s1 = b2 x0 - a2 x0.
void reset_notch_state(int nsections, int W, int lane, const double* coef, double x0, double* state) {
  check_lanes(nsections, W, lane);
  for (int k = 0; k < nsections; ++k) {
    const double b0 = coef[(5 * k + 0) * W + lane];
    const double b2 = coef[(5 * k + 2) * W + lane];
    const double a2 = coef[(5 * k + 4) * W + lane];
    state[(2 * k + 0) * W + lane] = x0 - b0 * x0;
    state[(2 * k + 1) * W + lane] = b2 * x0 - a2 * x0;
  }
}

}  // namespace ff
