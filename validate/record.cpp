#include "validate/record.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/errors.hpp"
#include "common/files.hpp"
#include "common/text.hpp"

namespace ff {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    cells.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') cells.emplace_back();
  return cells;
}

// The first sample at which x's running swing (max - min so far) exceeds `limit`, or x.size().
std::size_t first_swing_over(const std::vector<double>& x, double limit) {
  double lo = x.empty() ? 0.0 : x[0], hi = lo;
  for (std::size_t k = 0; k < x.size(); ++k) {
    lo = std::min(lo, x[k]);
    hi = std::max(hi, x[k]);
    if (hi - lo > limit) return k;
  }
  return x.size();
}

}  // namespace

Record read_record_csv(const std::string& path, const std::vector<std::string>& required) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path, 0, "", "cannot open the record");
  Record r;
  r.source = path;
  std::string line;
  if (!std::getline(in, line)) throw ConfigError(path, 1, "", "the record is empty (expected a header row)");
  const auto header = split(strip_bom(line));
  check_csv_header(header, path);
  int tcol = -1;
  for (std::size_t c = 0; c < header.size(); ++c)
    if (header[c] == "t") tcol = static_cast<int>(c);
  if (tcol < 0) throw ConfigError(path, 1, "t", "missing column 't' (time, s)");
  for (const auto& name : required)
    if (std::find(header.begin(), header.end(), name) == header.end())
      throw ConfigError(path, 1, name, "missing column '" + name + "', needed here");
  std::vector<std::vector<double>> cols(header.size());
  std::vector<int> lines;  // each sample's line in the file
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line == "\r") continue;
    const auto cells = split(line);
    if (cells.size() != header.size())
      throw ConfigError(path, line_no, "", "expected " + std::to_string(header.size()) + " cells, found " +
                                               std::to_string(cells.size()));
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const char* s = cells[c].c_str();
      char* end = nullptr;
      const double x = std::strtod(s, &end);
      // An empty cell: the channel was not sampled at this row (a slower logger channel); it holds its last
      // value (sample and hold, as the model's sensors.<channel>.rate predicts it). Time and the first row
      // must be complete.
      if (cells[c].empty()) {
        if (static_cast<int>(c) == tcol) throw ConfigError(path, line_no, header[c], "empty cell (every row needs its time)");
        if (cols[c].empty())
          throw ConfigError(path, line_no, header[c],
                            "empty cell in the first row (a channel logged at a slower rate needs its first value here)");
        cols[c].push_back(cols[c].back());
        ++r.held[header[c]];
        continue;
      }
      if (end == s || *end != '\0') throw ConfigError(path, line_no, header[c], "'" + cells[c] + "' is not a number");
      if (!std::isfinite(x)) throw ConfigError(path, line_no, header[c], "'" + cells[c] + "' is not finite");
      cols[c].push_back(x);
    }
    lines.push_back(line_no);
    const auto& t = cols[tcol];
    if (t.size() > 1 && !(t.back() > t[t.size() - 2]))
      throw ConfigError(path, line_no, "t", "time does not increase (" + cells[tcol] + " after " +
                                                std::to_string(t[t.size() - 2]) + ")");
  }
  if (cols[tcol].size() < kMinRecordSamples)
    throw ConfigError(path, line_no, "t", "the record ends here after only " + std::to_string(cols[tcol].size()) +
                                              " samples (rows); at least " + std::to_string(kMinRecordSamples) +
                                              " are needed");
  r.t = std::move(cols[tcol]);
  for (std::size_t c = 0; c < header.size(); ++c)
    if (static_cast<int>(c) != tcol) r.columns[header[c]] = std::move(cols[c]);
  // Angles in radians: a swing beyond 2 pi in a record of an arm that turns less than a turn is
  // degrees. The error names the sample where the swing first passes 2 pi.
  for (const char* name : {"ref", "hub_angle", "tip_angle"}) {
    if (!r.has(name)) continue;
    const auto& x = r.at(name);
    const std::size_t k = first_swing_over(x, 2.0 * M_PI);
    if (k < x.size())
      throw ConfigError(path, lines[k], name,
                        "swings over 2 pi by here (" + std::to_string(x[k]) +
                            "): looks like degrees; the record must be in radians");
  }
  // Rates in rad/s: the rate's integral must swing no more than 2 pi, nor much more than the hub
  // angle does (deg/s would make it 57 times the angle's swing).
  if (r.has("hub_rate")) {
    const auto& w = r.at("hub_rate");
    std::vector<double> integral(w.size(), 0.0);
    for (std::size_t k = 1; k < w.size(); ++k) integral[k] = integral[k - 1] + 0.5 * (w[k] + w[k - 1]) * (r.t[k] - r.t[k - 1]);
    double limit = 2.0 * M_PI;
    bool by_angle = false;
    if (r.has("hub_angle")) {
      const auto [lo, hi] = std::minmax_element(r.at("hub_angle").begin(), r.at("hub_angle").end());
      by_angle = 10.0 * std::max(*hi - *lo, 0.01) < limit;
      if (by_angle) limit = 10.0 * std::max(*hi - *lo, 0.01);
    }
    const std::size_t k = first_swing_over(integral, limit);
    if (k < w.size())
      throw ConfigError(path, lines[k], "hub_rate",
                        "its integral swings over " + std::to_string(limit) + " rad by here" +
                            (by_angle ? " (ten times the hub angle's swing)" : "") +
                            ": looks like degrees per second; the record must be in rad/s");
  }
  return r;
}

void write_record_csv(const Record& r, const std::vector<std::string>& order, const std::string& path, int digits) {
  std::string text = "t";
  for (const auto& c : order) text += "," + c;
  text += "\n";
  char buf[64];
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    if (digits > 0) std::snprintf(buf, sizeof buf, "%.*g", digits, r.t[k]);
    else std::snprintf(buf, sizeof buf, "%.6f", r.t[k]);
    text += buf;
    for (const auto& c : order) {
      std::snprintf(buf, sizeof buf, ",%.*g", digits > 0 ? digits : 10, r.at(c)[k]);
      text += buf;
    }
    text += "\n";
  }
  write_file_atomic(path, text);
}

std::vector<double> time_derivative(const std::vector<double>& t, const std::vector<double>& y) {
  const std::size_t n = y.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k > 0 ? k - 1 : 0, b = k + 1 < n ? k + 1 : n - 1;
    d[k] = (y[b] - y[a]) / (t[b] - t[a]);
  }
  return d;
}

double interpolate(const std::vector<double>& t, const std::vector<double>& y, double x) {
  if (x <= t.front()) return y.front();
  if (x >= t.back()) return y.back();
  const auto it = std::upper_bound(t.begin(), t.end(), x);
  const std::size_t k = static_cast<std::size_t>(it - t.begin());
  const double u = (x - t[k - 1]) / (t[k] - t[k - 1]);
  return y[k - 1] + u * (y[k] - y[k - 1]);
}

namespace {

// A cubic a0 + a1 s + a2 s^2 + a3 s^3 in s = x - c.
struct Cubic {
  double c = 0.0, a[4] = {};
  double value(double x) const { const double s = x - c; return a[0] + s * (a[1] + s * (a[2] + s * a[3])); }
  double rate(double x) const { const double s = x - c; return a[1] + s * (2 * a[2] + s * 3 * a[3]); }
  double accel(double x) const { return 2 * a[2] + 6 * a[3] * (x - c); }
};

// The interpolating polynomial through (t, y)[lo, lo + m), m <= 4, about c = t[lo]: Newton's divided
// differences, expanded into powers of s.
Cubic fit_cubic(const std::vector<double>& t, const std::vector<double>& y, std::size_t lo, std::size_t m) {
  double d[4], x[4];
  for (std::size_t j = 0; j < m; ++j) x[j] = t[lo + j] - t[lo], d[j] = y[lo + j];
  for (std::size_t l = 1; l < m; ++l)
    for (std::size_t j = m - 1; j >= l; --j) d[j] = (d[j] - d[j - 1]) / (x[j] - x[j - l]);
  Cubic p;
  p.c = t[lo];
  p.a[0] = d[m - 1];
  for (std::size_t k = m - 1; k-- > 0;) {  // p <- p (s - x_k) + d_k
    for (std::size_t j = m - 1; j > 0; --j) p.a[j] = p.a[j - 1] - x[k] * p.a[j];
    p.a[0] = d[k] - x[k] * p.a[0];
  }
  return p;
}

}  // namespace

SmoothSamples sample_piecewise_smooth(const std::vector<double>& t, const std::vector<double>& y, double t0, double T,
                                      long n) {
  const std::size_t N = t.size();
  if (N < 2) throw std::invalid_argument("sample_piecewise_smooth: fewer than two samples");
  const std::size_t m = std::min<std::size_t>(N, 4);
  // Each interval's cubic: of the (up to three) four-sample stencils holding [t_i, t_i+1], the one with the
  // smallest third divided difference, a3 of its cubic.
  std::vector<Cubic> p(N - 1);
  for (std::size_t i = 0; i + 1 < N; ++i) {
    const std::size_t first = i + 2 >= m ? i + 2 - m : 0, last = std::min(i, N - m);
    p[i] = fit_cubic(t, y, first, m);
    for (std::size_t lo = first + 1; lo <= last; ++lo)
      if (const Cubic c = fit_cubic(t, y, lo, m); std::abs(c.a[3]) < std::abs(p[i].a[3])) p[i] = c;
  }
  // Knots: interval i when its neighbours' cubics differ in y'' at its middle by more than 2 h (|y'''_l| +
  // |y'''_r|) + 1e-3 max |y''| and their slopes agree somewhere inside it (there the knot is).
  double peak = 0.0;
  for (std::size_t i = 0; i + 1 < N; ++i) peak = std::max(peak, std::abs(p[i].accel(0.5 * (t[i] + t[i + 1]))));
  std::vector<double> knot(p.size(), NAN);  // the knot's time in interval i, NaN = none
  for (std::size_t i = 1; i + 2 < N; ++i) {
    const Cubic &l = p[i - 1], &r = p[i + 1];
    const double h = t[i + 1] - t[i], mid = t[i] + 0.5 * h;
    if (std::abs(r.accel(mid) - l.accel(mid)) <= 12 * h * (std::abs(l.a[3]) + std::abs(r.a[3])) + 1e-3 * peak) continue;
    // The slopes' difference, a quadratic A s^2 + B s + C in s = x - t_i: its root in the interval
    // nearest the middle (no knot when it has none).
    const double sl = t[i] - l.c, sr = t[i] - r.c;
    const double A = 3 * (r.a[3] - l.a[3]);
    const double B = 2 * (r.a[2] - l.a[2]) + 6 * (r.a[3] * sr - l.a[3] * sl);
    const double C = r.rate(t[i]) - l.rate(t[i]);
    double best = NAN;
    std::vector<double> roots;
    if (std::abs(A) * h > 1e-12 * std::abs(B)) {
      const double disc = B * B - 4 * A * C;
      if (disc >= 0) roots = {(-B + std::sqrt(disc)) / (2 * A), (-B - std::sqrt(disc)) / (2 * A)};
    } else if (B != 0) {
      roots = {-C / B};
    }
    double dist = INFINITY;
    for (double s : roots)
      if (s >= 0 && s <= h && std::abs(s - 0.5 * h) < dist) dist = std::abs(s - 0.5 * h), best = s;
    knot[i] = t[i] + best;  // NaN (no knot) when no root is inside
  }
  SmoothSamples out;
  out.value.resize(n);
  out.rate.resize(n);
  out.accel.resize(n);
  for (long k = 0; k < n; ++k) {
    const double x = std::clamp(t0 + static_cast<double>(k) * T, t.front(), t.back());
    std::size_t i = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin());
    i = std::min(i > 0 ? i - 1 : 0, p.size() - 1);
    const Cubic& c = std::isnan(knot[i]) ? p[i] : x < knot[i] ? p[i - 1] : p[i + 1];
    out.value[k] = x == t[i] ? y[i] : c.value(x);  // on a sample: the sample
    out.rate[k] = c.rate(x);
    out.accel[k] = c.accel(x);
  }
  return out;
}

}  // namespace ff
