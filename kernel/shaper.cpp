#include "kernel/shaper.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace ff {

namespace {

// EI amplitudes and times (Singhose, Seering & Singer 1994). Undamped: the closed form A = (1+V)/4,
// (1-V)/2, (1+V)/4 at 0, T/2, T. Damped: that start refined by Newton's method on the EI conditions:
// the residual vibration equals vtol at the design frequency and peaks there (zero slope), the hump is
// symmetric (equal residual at 0.9 and 1.1 omega), the impulses are evenly spaced; amplitudes sum to 1.
std::vector<Impulse> make_ei(double omega, double zeta, double vtol) {
  const double wd = omega * std::sqrt(1.0 - zeta * zeta);
  const double td = 2.0 * std::numbers::pi / wd;
  double a1 = (1.0 + vtol) / 4.0, a2 = (1.0 - vtol) / 2.0, t2 = td / 2.0, t3 = td;
  if (zeta == 0.0) return {{0.0, a1}, {t2, a2}, {t3, 1.0 - a1 - a2}};
  // Unknowns x = (a1, a2, t2, t3), a3 = 1 - a1 - a2.
  auto residuals = [&](const double* x, double* f) {
    const std::vector<Impulse> s = {{0.0, x[0]}, {x[2], x[1]}, {x[3], 1.0 - x[0] - x[1]}};
    const double h = 1e-6 * omega;
    f[0] = calc_residual_vibration(s, omega, zeta) - vtol;
    f[1] = (calc_residual_vibration(s, omega + h, zeta) - calc_residual_vibration(s, omega - h, zeta)) / (2 * h) * omega;
    // Symmetric hump: equal residual at omega (1 -/+ 0.1).
    f[2] = calc_residual_vibration(s, omega * 0.9, zeta) - calc_residual_vibration(s, omega * 1.1, zeta);
    f[3] = x[3] - 2.0 * x[2];  // impulses evenly spaced in time
  };
  double x[4] = {a1, a2, t2, t3};
  for (int it = 0; it < 50; ++it) {
    double f[4], jac[4][4];
    residuals(x, f);
    if (std::fabs(f[0]) + std::fabs(f[1]) + std::fabs(f[2]) + std::fabs(f[3]) < 1e-13) break;
    for (int j = 0; j < 4; ++j) {
      double xp[4] = {x[0], x[1], x[2], x[3]};
      const double step = 1e-7 * std::max(1.0, std::fabs(x[j]));
      xp[j] += step;
      double fp[4];
      residuals(xp, fp);
      for (int i = 0; i < 4; ++i) jac[i][j] = (fp[i] - f[i]) / step;
    }
    // Solve jac dx = -f by Gaussian elimination with partial pivoting.
    double a[4][5];
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) a[i][j] = jac[i][j];
      a[i][4] = -f[i];
    }
    for (int c = 0; c < 4; ++c) {
      int p = c;
      for (int r = c + 1; r < 4; ++r)
        if (std::fabs(a[r][c]) > std::fabs(a[p][c])) p = r;
      for (int k = 0; k < 5; ++k) std::swap(a[c][k], a[p][k]);
      for (int r = c + 1; r < 4; ++r) {
        const double m = a[r][c] / a[c][c];
        for (int k = c; k < 5; ++k) a[r][k] -= m * a[c][k];
      }
    }
    double dx[4];
    for (int r = 3; r >= 0; --r) {
      double sum = a[r][4];
      for (int k = r + 1; k < 4; ++k) sum -= a[r][k] * dx[k];
      dx[r] = sum / a[r][r];
    }
    for (int j = 0; j < 4; ++j) x[j] += dx[j];
  }
  return {{0.0, x[0]}, {x[2], x[1]}, {x[3], 1.0 - x[0] - x[1]}};
}

}  // namespace

std::vector<Impulse> make_shaper(ShaperKind kind, double omega, double zeta, double vtol) {
  if (kind == ShaperKind::kNone) return {{0.0, 1.0}};
  if (!(omega > 0) || !std::isfinite(omega)) throw std::invalid_argument("shaper: frequency must be > 0");
  if (!(zeta >= 0 && zeta < 1)) throw std::invalid_argument("shaper: damping must be in [0, 1)");
  if (!(vtol > 0 && vtol < 0.5)) throw std::invalid_argument("shaper: vtol must be in (0, 0.5)");
  // K = exp(-zeta pi / sqrt(1 - zeta^2)), half damped period T/2 = pi / omega_d.
  const double sq = std::sqrt(1.0 - zeta * zeta);
  const double k = std::exp(-zeta * std::numbers::pi / sq);
  const double half = std::numbers::pi / (omega * sq);
  switch (kind) {
    case ShaperKind::kZv: return {{0.0, 1.0 / (1.0 + k)}, {half, k / (1.0 + k)}};
    case ShaperKind::kZvd: {
      const double d = 1.0 + 2.0 * k + k * k;
      return {{0.0, 1.0 / d}, {half, 2.0 * k / d}, {2.0 * half, k * k / d}};
    }
    case ShaperKind::kEi: return make_ei(omega, zeta, vtol);
    case ShaperKind::kNone: break;
  }
  return {{0.0, 1.0}};
}

double calc_residual_vibration(const std::vector<Impulse>& s, double omega, double zeta) {
  // V = e^{-zeta omega t_N} sqrt(C^2 + S^2), C = sum A_i e^{zeta omega t_i} cos(omega_d t_i), S likewise with sin.
  const double wd = omega * std::sqrt(1.0 - zeta * zeta);
  const double tn = s.back().time;
  double c = 0.0, si = 0.0;
  for (const auto& p : s) {
    const double e = std::exp(zeta * omega * (p.time - tn));
    c += p.amplitude * e * std::cos(wd * p.time);
    si += p.amplitude * e * std::sin(wd * p.time);
  }
  return std::sqrt(c * c + si * si);
}

double calc_insensitivity(const std::vector<Impulse>& s, double w0, double zeta, double level) {
  // Walk out from the design frequency on a fine grid, then bisect each edge.
  auto edge = [&](double dir) {
    double lo = 1.0, hi = 1.0;
    for (int i = 1; i <= 20000; ++i) {
      hi = 1.0 + dir * 1e-4 * i;
      if (calc_residual_vibration(s, w0 * hi, zeta) > level) break;
      lo = hi;
    }
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (calc_residual_vibration(s, w0 * mid, zeta) > level ? hi : lo) = mid;
    }
    return lo;
  };
  return edge(+1.0) - edge(-1.0);
}

}  // namespace ff
