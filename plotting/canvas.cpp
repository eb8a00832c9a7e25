// Shared drawing toolkit of the plotting library (see canvas.hpp).
#include "plotting/canvas.hpp"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <dlfcn.h>
#include <png.h>

#include <opencv2/videoio.hpp>  // the backends' and codecs' names only: the writer is a module
#pragma GCC diagnostic pop

#include <array>
#include <cctype>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <system_error>

#include "common/files.hpp"

namespace ff::canvas {

// ---------------------------------------------------------------- colours

cv::Scalar bgr(Rgb c) { return {double(c.b), double(c.g), double(c.r)}; }

cv::Scalar mix(const cv::Scalar& a, const cv::Scalar& b, double t) { return a * (1 - t) + b * t; }

std::vector<int> assign_colours(const std::vector<int>& requested) {
  const size_t n = size_t(palette_size());
  std::vector<bool> taken(n, false);
  for (int c : requested)
    if (c >= 0) taken[size_t(c) % n] = true;
  std::vector<int> out;
  size_t next = 0, auto_count = 0;
  for (int c : requested) {
    if (c >= 0) { out.push_back(c); continue; }
    while (next < taken.size() && taken[next]) ++next;
    out.push_back(next < taken.size() ? int(next++) : int(auto_count % n));
    ++auto_count;
  }
  return out;
}

// ---------------------------------------------------------------- nice ticks

namespace {

// A tick step m × 10^e with m in {1, 2, 5}; kept apart so tick values can be computed exactly.
struct NiceStep {
  int mantissa;
  int exponent;
  double value() const { return mantissa * std::pow(10.0, exponent); }
  // k-th multiple of the step, divided rather than multiplied by 10^-e so 3 × 0.2 prints as 0.6.
  double multiple(long long k) const {
    const double km = double(k) * mantissa;
    return exponent >= 0 ? km * std::pow(10.0, exponent) : km / std::pow(10.0, -exponent);
  }
};

// The 1-2-5 step nearest to `raw`.
NiceStep nice_step_near(double raw) {
  int e = int(std::floor(std::log10(raw)));
  const double f = raw / std::pow(10.0, e);
  int m = f < 1.5 ? 1 : f < 3.0 ? 2 : f < 7.0 ? 5 : 10;
  if (m == 10) m = 1, ++e;
  return {m, e};
}

// The smallest 1-2-5 step >= `raw`.
NiceStep nice_step_at_least(double raw) {
  NiceStep s = nice_step_near(raw);
  while (s.value() < raw * (1 - 1e-12)) s = s.mantissa == 1 ? NiceStep{2, s.exponent}
                                           : s.mantissa == 2 ? NiceStep{5, s.exponent}
                                                             : NiceStep{1, s.exponent + 1};
  return s;
}

// The next smaller 1-2-5 step.
NiceStep smaller(NiceStep s) {
  if (s.mantissa == 1) return {5, s.exponent - 1};
  return {s.mantissa == 5 ? 2 : 1, s.exponent};
}

// Multiples of `s` inside [lo, hi], with a tolerance of a billionth of a step at either end.
std::vector<double> multiples_inside(double lo, double hi, NiceStep s) {
  const double step = s.value(), eps = step * 1e-9;
  const auto k0 = (long long)std::ceil((lo - eps) / step);
  const auto k1 = (long long)std::floor((hi + eps) / step);
  std::vector<double> out;
  for (long long k = k0; k <= k1 && out.size() < 1000; ++k) out.push_back(k == 0 ? 0.0 : s.multiple(k));
  return out;
}

}  // namespace

std::pair<double, double> widened(double lo, double hi) {
  if (lo > hi) std::swap(lo, hi);
  const double mag = std::max(std::abs(lo), std::abs(hi));
  if (hi - lo > mag * 1e-12 && hi - lo > 0) return {lo, hi};
  const double half = mag > 0 ? mag * 0.1 : 1.0;
  return {lo - half, hi + half};
}

Ticks nice_ticks(double lo, double hi, int target, double min_step) {
  if (!std::isfinite(lo) || !std::isfinite(hi))
    throw std::invalid_argument("calc_nice_ticks: range must be finite");
  std::tie(lo, hi) = widened(lo, hi);
  if (!std::isfinite(hi - lo)) return {{lo, hi}, hi / 2 - lo / 2, {}};
  NiceStep s = nice_step_near((hi - lo) / std::max(target - 1, 1));
  const std::optional<NiceStep> floor_step =
      min_step > 0 ? std::optional(nice_step_at_least(min_step)) : std::nullopt;
  if (floor_step && s.value() < floor_step->value()) s = *floor_step;
  for (;;) {
    auto v = multiples_inside(lo, hi, s);
    if (v.size() >= 2 || (floor_step && s.value() <= floor_step->value() * (1 + 1e-12)))
      return {std::move(v), s.value(), {}};
    s = smaller(s);
  }
}

// ---------------------------------------------------------------- text

namespace {

// ASCII spellings of UTF-8 signs the Hershey font cannot draw.
constexpr std::array<std::pair<std::string_view, std::string_view>, 26> kAsciiFor{{
    {"\u00b7", "."},     {"\u00b1", "+/-"},   {"\u00b0", "deg"},   {"\u00b5", "u"},
    {"\u03bc", "u"},     {"\u00b2", "^2"},    {"\u00b3", "^3"},    {"\u00d7", "x"},
    {"\u2212", "-"},     {"\u2013", "-"},     {"\u2014", "-"},     {"\u00a0", " "},
    {"\u2009", " "},     {"\u202f", " "},     {"\u0394", "Delta"}, {"\u03b8", "theta"},
    {"\u03c9", "omega"}, {"\u03c4", "tau"},   {"\u03b1", "alpha"}, {"\u03c6", "phi"},
    {"\u03b6", "zeta"},  {"\u03c3", "sigma"}, {"\u03c0", "pi"},    {"\u2248", "~"},
    {"\u2264", "<="},    {"\u2265", ">="},
}};

constexpr int kFace = cv::FONT_HERSHEY_SIMPLEX;

}  // namespace

std::string hershey_text(std::string_view s) {
  std::string out;
  for (size_t i = 0; i < s.size();) {
    if ((unsigned char)s[i] < 0x80) { out += s[i++]; continue; }
    const auto hit = std::find_if(kAsciiFor.begin(), kAsciiFor.end(),
                                  [&](const auto& p) { return s.substr(i).starts_with(p.first); });
    if (hit != kAsciiFor.end()) { out += hit->second; i += hit->first.size(); continue; }
    out += '?';
    for (++i; i < s.size() && ((unsigned char)s[i] & 0xC0) == 0x80; ++i) {}  // skip continuation bytes
  }
  return out;
}

TextSize measure(const std::string& t, const Font& f) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(t, kFace, f.scale, f.thickness, &base);
  return {sz.width, sz.height, base};
}

int line_height(const Font& f) { return measure("Ag(", f).height(); }

Font fitted(const std::string& t, Font f, int max_width) {
  const int w = measure(t, f).width;
  if (w > max_width && w > 0) f.scale *= double(max_width) / w;
  return f;
}

void put_text(cv::Mat& img, const std::string& t, cv::Point at, HAlign h, VAlign v, const Font& f,
              const cv::Scalar& colour) {
  const TextSize ts = measure(t, f);
  const int x = h == HAlign::left ? at.x : h == HAlign::centre ? at.x - ts.width / 2 : at.x - ts.width;
  const int y = v == VAlign::top ? at.y + ts.ascent : v == VAlign::middle ? at.y + ts.ascent / 2 : at.y - ts.descent;
  cv::putText(img, t, {x, y}, kFace, f.scale, colour, f.thickness, cv::LINE_AA);
}

cv::Mat rotated_text(const std::string& t, const Font& f, const cv::Scalar& colour) {
  const TextSize ts = measure(t, f);
  cv::Mat patch(ts.height() + 2, ts.width + 2, CV_8UC3, kWhite);
  put_text(patch, t, {1, 1}, HAlign::left, VAlign::top, f, colour);
  cv::Mat turned;
  cv::rotate(patch, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  return turned;
}

void paste(cv::Mat& img, const cv::Mat& patch, cv::Point tl) {
  const cv::Rect dst = cv::Rect(tl, patch.size()) & cv::Rect({0, 0}, img.size());
  if (dst.empty()) return;
  patch(cv::Rect(dst.tl() - tl, dst.size())).copyTo(img(dst));
}

// ---------------------------------------------------------------- style

Style style_at(double s) {
  const int thin = std::max(1, int(std::lround(s))), bold = s < 0.7 ? 1 : std::max(2, int(std::lround(2 * s)));
  return {s, {1.0 * s, bold}, {0.75 * s, thin}, {0.62 * s, thin}, {0.62 * s, thin},
          int(std::lround(16 * s)), int(std::lround(9 * s)), int(std::lround(7 * s))};
}

Style style_for(cv::Size size) {
  return style_at(std::clamp(std::min(size.width / 1400.0, size.height / 800.0), 0.6, 4.0));
}

void check_image_size(const std::string& what, int width, int height, int min_w, int min_h) {
  if (width < min_w || height < min_h || width > 20000 || height > 20000)
    throw std::invalid_argument(what + ": size " + std::to_string(width) + "x" + std::to_string(height) +
                                " outside " + std::to_string(min_w) + "x" + std::to_string(min_h) +
                                " .. 20000x20000");
}

// ---------------------------------------------------------------- axes

Range resolve_range(double fixed_lo, double fixed_hi, double data_lo, double data_hi, double margin) {
  if (!std::isfinite(data_lo)) data_lo = std::isfinite(fixed_lo) ? fixed_lo : 0.0;
  if (!std::isfinite(data_hi)) data_hi = std::isfinite(fixed_hi) ? fixed_hi : 1.0;
  auto [lo, hi] = widened(data_lo, data_hi);
  const double m = margin * (hi - lo);
  lo = std::isfinite(fixed_lo) ? fixed_lo : lo - m;
  hi = std::isfinite(fixed_hi) ? fixed_hi : hi + m;
  std::tie(lo, hi) = widened(lo, hi);
  return {lo, hi};
}

namespace {

// Widest tick label of `t`.
int widest_label(const Ticks& t, const Font& f) {
  int w = 0;
  for (size_t i = 0; i < t.values.size(); ++i) w = std::max(w, measure(t.label(i), f).width);
  return w;
}

// Every `stride`-th tick of `t`, starting with the first.
Ticks thinned(const Ticks& t, size_t stride) {
  if (stride <= 1) return t;
  Ticks out{{}, t.step * double(stride), {}};
  for (size_t i = 0; i < t.values.size(); i += stride) {
    out.values.push_back(t.values[i]);
    if (!t.labels.empty()) out.labels.push_back(t.label(i));
  }
  return out;
}

// Smallest gap between neighbouring tick values, in px along an axis of `length` px.
double min_spacing(const Ticks& t, Range r, int length) {
  double d = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i < t.values.size(); ++i) d = std::min(d, std::abs(t.values[i] - t.values[i - 1]));
  return d / (r.hi - r.lo) * length;
}

// Y ticks about every 90 px of area height.
Ticks y_ticks_for(Range y, int area_height, double s, double min_step) {
  return nice_ticks(y.lo, y.hi, std::clamp(int(area_height / (90 * s)), 3, 10), min_step);
}

// X ticks about every 140 px, fewer while neighbouring labels would come closer than 2 gaps.
Ticks x_ticks_for(Range x, int area_width, const Style& st) {
  for (int target = std::clamp(int(area_width / (140 * st.s)), 3, 12);; --target) {
    Ticks t = nice_ticks(x.lo, x.hi, target);
    const double spacing = t.step / (x.hi - x.lo) * area_width;
    if (target <= 2 || spacing >= widest_label(t, st.tick) + 3 * st.gap) return t;
  }
}

// Fixed y ticks thinned so labels are at least 2.2 text heights apart.
Ticks fit_fixed_y(const Ticks& t, Range y, int area_height, const Style& st) {
  const double spacing = min_spacing(t, y, area_height), need = 2.2 * measure("0", st.tick).ascent;
  return thinned(t, spacing >= need ? 1 : size_t(std::ceil(need / std::max(spacing, 1e-9))));
}

// Fixed x tick labels laid out to fit: the font shrunk to `opt.x_min_font` at most, on one row
// or (with opt.x_stagger, once the font would go below 80 %) alternating over two; every k-th
// label only if even that is too crowded.
struct FixedX {
  Ticks ticks;
  Font font;
  int rows;
};

FixedX fit_fixed_x(const Ticks& t, Range x, int area_width, const Style& st, const AxesOptions& opt) {
  const double spacing = min_spacing(t, x, area_width);
  const int w = std::max(1, widest_label(t, st.tick));
  const auto scale_for = [&](int rows) { return std::clamp((spacing * rows - 2 * st.gap) / w, opt.x_min_font, 1.0); };
  const auto fits = [&](int rows, double scale) { return w * scale + 2 * st.gap <= spacing * rows; };
  const auto font = [&](double scale) { return Font{st.tick.scale * scale, st.tick.thickness}; };
  const double one = scale_for(1);
  if (fits(1, one) && (!opt.x_stagger || one >= 0.8)) return {t, font(one), 1};
  const int rows = opt.x_stagger ? 2 : 1;
  const double scale = scale_for(rows);
  const double need = w * scale + 2 * st.gap;
  return {thinned(t, fits(rows, scale) ? 1 : size_t(std::ceil(need / std::max(spacing * rows, 1e-9)))), font(scale),
          rows};
}

}  // namespace

Axes layout_axes(cv::Size img, Range x, Range y, const AxesText& text, const Style& st, const AxesOptions& opt) {
  const int tick_h = measure("0", st.tick).ascent;
  const int top = st.pad + std::max(text.title.empty() ? 0 : line_height(st.title) + st.gap, tick_h);
  // One pass per number of x label rows: the rows need height, which changes the y ticks, which
  // change the left margin and so the room for the x labels.
  const auto pass = [&](int extra_rows) {
    const int bottom = st.tick_len + st.gap + tick_h + st.pad + extra_rows * (tick_h + st.gap) +
                       (text.x_label.empty() ? 0 : st.gap + line_height(st.label));
    const int area_h = std::max(10, img.height - top - bottom);
    Ticks yt = opt.y_ticks ? fit_fixed_y(*opt.y_ticks, y, area_h, st) : y_ticks_for(y, area_h, st.s, opt.y_min_step);
    const int left = st.pad + (text.y_label.empty() ? 0 : line_height(st.label) + st.gap) +
                     widest_label(yt, st.tick) + st.gap + st.tick_len;
    // Right margin leaves room for half of the last x label; two passes since ticks depend on width.
    const auto x_ticks = [&](int width) {
      return opt.x_ticks ? fit_fixed_x(*opt.x_ticks, x, width, st, opt) : FixedX{x_ticks_for(x, width, st), st.tick, 1};
    };
    int right = st.pad + opt.reserve_right;
    FixedX xt = x_ticks(std::max(10, img.width - left - right));
    right = std::max(st.pad, widest_label(xt.ticks, xt.font) / 2 + st.gap) + opt.reserve_right;
    xt = x_ticks(std::max(10, img.width - left - right));
    const cv::Rect area(left, top, std::max(10, img.width - left - right), area_h);
    return Axes{area, x, y, std::move(xt.ticks), std::move(yt), xt.font, st.tick, xt.rows};
  };
  Axes a = pass(0);
  if (a.x_label_rows > 1) a = pass(a.x_label_rows - 1);
  return a;
}

void draw_grid(cv::Mat& img, const Axes& a, bool x_lines, bool y_lines) {
  const int x0 = a.area.x, x1 = a.area.x + a.area.width - 1;
  const int y0 = a.area.y, y1 = a.area.y + a.area.height - 1;
  if (x_lines)
    for (double v : a.x_ticks.values) cv::line(img, {a.ix(v), y0}, {a.ix(v), y1}, kGridColour, 1);
  if (y_lines)
    for (double v : a.y_ticks.values) cv::line(img, {x0, a.iy(v)}, {x1, a.iy(v)}, kGridColour, 1);
}

void draw_frame_and_ticks(cv::Mat& img, const Axes& a, const Style& st) {
  const cv::Rect& r = a.area;
  cv::rectangle(img, {r.x - 1, r.y - 1}, {r.x + r.width, r.y + r.height}, kFrameColour, 1);
  const int below = r.y + r.height, left = r.x - 1;
  // X ticks and labels, kept inside the image at the ends.
  for (size_t i = 0; i < a.x_ticks.values.size(); ++i) {
    const int X = a.ix(a.x_ticks.values[i]);
    cv::line(img, {X, below}, {X, below + st.tick_len}, kFrameColour, 1);
    const std::string t = a.x_ticks.label(i);
    const int half = measure(t, a.x_font).width / 2;
    const int cx = std::clamp(X, half + 2, img.cols - half - 2);
    const int row = int(i % size_t(std::max(1, a.x_label_rows))) * (measure("0", st.tick).ascent + st.gap);
    put_text(img, t, {cx, below + st.tick_len + st.gap + row}, HAlign::centre, VAlign::top, a.x_font, kTickTextColour);
  }
  // Y ticks and labels, right-aligned against the ticks.
  for (size_t i = 0; i < a.y_ticks.values.size(); ++i) {
    const int Y = a.iy(a.y_ticks.values[i]);
    cv::line(img, {left - st.tick_len, Y}, {left, Y}, kFrameColour, 1);
    put_text(img, a.y_ticks.label(i), {left - st.tick_len - st.gap, Y}, HAlign::right, VAlign::middle, a.y_font,
             kTickTextColour);
  }
}

void draw_axes_text(cv::Mat& img, const Axes& a, const AxesText& text, const Style& st) {
  const cv::Rect& r = a.area;
  if (!text.x_label.empty()) {
    const Font f = fitted(text.x_label, st.label, img.cols - 2 * st.pad);
    const int cx = std::clamp(r.x + r.width / 2, measure(text.x_label, f).width / 2 + st.pad,
                              img.cols - measure(text.x_label, f).width / 2 - st.pad);
    put_text(img, text.x_label, {cx, img.rows - st.pad}, HAlign::centre, VAlign::bottom, f, kTextColour);
  }
  if (!text.y_label.empty()) {
    const cv::Mat patch =
        rotated_text(text.y_label, fitted(text.y_label, st.label, img.rows - 2 * st.pad), kTextColour);
    const int cy = std::clamp(r.y + r.height / 2, patch.rows / 2 + 1, img.rows - patch.rows / 2 - 1);
    paste(img, patch, {st.pad, cy - patch.rows / 2});
  }
  if (!text.title.empty()) {
    const Font f = fitted(text.title, st.title, img.cols - 2 * st.pad);
    const int half = measure(text.title, f).width / 2;
    const int cx = std::clamp(r.x + r.width / 2, half + st.pad, img.cols - half - st.pad);
    put_text(img, text.title, {cx, st.pad}, HAlign::centre, VAlign::top, f, kTextColour);
  }
}

// ---------------------------------------------------------------- polylines

namespace {

// Cuts segment a-b to rectangle r (Liang-Barsky); false if nothing is left.
bool clip_segment(cv::Point2d& a, cv::Point2d& b, const cv::Rect2d& r) {
  double t0 = 0, t1 = 1;
  const double d[2] = {b.x - a.x, b.y - a.y};
  const double p[4] = {-d[0], d[0], -d[1], d[1]};
  const double q[4] = {a.x - r.x, r.x + r.width - a.x, a.y - r.y, r.y + r.height - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) { if (q[i] < 0) return false; continue; }
    const double t = q[i] / p[i];
    if (p[i] < 0) t0 = std::max(t0, t); else t1 = std::min(t1, t);
  }
  if (t0 > t1) return false;
  const cv::Point2d a0 = a;
  a = a0 + t0 * (b - a0), b = a0 + t1 * (b - a0);
  return true;
}

// Dash and gap lengths for a stroke; the gap allows for the round caps.
std::pair<double, double> dash_pattern(const Stroke& k, const Style& st) {
  return {12 * st.s + k.thickness, 7 * st.s + k.thickness};
}

}  // namespace

std::vector<Polyline> pieces(const std::vector<double>& x, const std::vector<double>& y, const Axes& a,
                             const cv::Rect2d& clip) {
  std::vector<Polyline> out;
  const auto ok = [&](size_t i) { return i < x.size() && std::isfinite(x[i]) && std::isfinite(y[i]); };
  const auto at = [&](size_t i) { return cv::Point2d(a.ax(x[i]), a.ay(y[i])); };
  bool open = false;  // the last piece ends at point i-1 and may be continued
  for (size_t i = 0; i < x.size(); ++i) {
    if (!ok(i)) { open = false; continue; }
    if (i == 0 || !ok(i - 1)) {  // first point of a run; kept as a dot if the run has no second
      open = false;
      if (!ok(i + 1) && clip.contains(at(i))) out.push_back({at(i)});
      continue;
    }
    cv::Point2d p = at(i - 1), q = at(i);
    const cv::Point2d q0 = q;
    if (!clip_segment(p, q, clip)) { open = false; continue; }
    if (open && p == at(i - 1)) out.back().push_back(q);
    else out.push_back({p, q});
    open = q == q0;
  }
  return out;
}

void draw_solid(cv::Mat& img, const Polyline& pl, const cv::Scalar& c, int th) {
  if (pl.size() == 1) {
    cv::circle(img, fixed_point(pl[0]), std::max(2, th) * 16, c, cv::FILLED, cv::LINE_AA, kShift);
    return;
  }
  std::vector<cv::Point> pts;
  for (const auto& p : pl) pts.push_back(fixed_point(p));
  cv::polylines(img, pts, false, c, th, cv::LINE_AA, kShift);
}

void draw_dashed(cv::Mat& img, const Polyline& pl, const cv::Scalar& c, int th, double on, double off) {
  if (pl.size() == 1) return draw_solid(img, pl, c, th);
  bool drawing = true;
  double used = 0;  // length already spent in the current dash or gap
  for (size_t i = 1; i < pl.size(); ++i) {
    const cv::Point2d d = pl[i] - pl[i - 1];
    const double len = std::hypot(d.x, d.y);
    for (double pos = 0; pos < len;) {
      const double step = std::min((drawing ? on : off) - used, len - pos);
      if (drawing) cv::line(img, fixed_point(pl[i - 1] + d * (pos / len)),
                            fixed_point(pl[i - 1] + d * ((pos + step) / len)), c, th, cv::LINE_AA, kShift);
      pos += step, used += step;
      if (used >= (drawing ? on : off) - 1e-9) drawing = !drawing, used = 0;
    }
  }
}

void draw_stroke(cv::Mat& img, const Polyline& pl, const Stroke& k, const Style& st) {
  if (!k.dashed) return draw_solid(img, pl, k.colour, k.thickness);
  const auto [on, off] = dash_pattern(k, st);
  draw_dashed(img, pl, k.colour, k.thickness, on, off);
}

void draw_series(cv::Mat& roi, const Axes& a, const std::vector<double>& x, const std::vector<double>& y,
                 const Stroke& k, const Style& st) {
  const double m = 4.0 * k.thickness + 4;  // clip a little outside so caps at the edge look right
  const cv::Rect2d clip(-m, -m, roi.cols + 2 * m, roi.rows + 2 * m);
  for (const auto& pl : pieces(x, y, a, clip)) draw_stroke(roi, pl, k, st);
}

void fill_translucent(cv::Mat& img, const std::vector<Polyline>& polygons, const cv::Scalar& colour, double alpha) {
  std::vector<std::vector<cv::Point>> pts;
  for (const auto& pl : polygons) {
    if (pl.size() < 3) continue;
    auto& p = pts.emplace_back();
    for (const auto& q : pl) p.push_back(fixed_point(q));
  }
  if (pts.empty()) return;
  cv::Mat layer = img.clone();
  cv::fillPoly(layer, pts, colour, cv::LINE_AA, kShift);
  cv::addWeighted(img, 1 - alpha, layer, alpha, 0, img);
}

// ---------------------------------------------------------------- legend

namespace {

// Number of "ink" pixels (darker than the grid) in `r` of `img`.
int ink_in(const cv::Mat& img, const cv::Rect& r) {
  const cv::Rect inside = r & cv::Rect({0, 0}, img.size());
  if (inside.empty()) return 0;
  cv::Mat grey;
  cv::cvtColor(img(inside), grey, cv::COLOR_BGR2GRAY);
  return cv::countNonZero(grey < 200);
}

struct LegendMetrics {
  int sample, row;
};

LegendMetrics legend_metrics(const Style& st) { return {st.px(40), int(line_height(st.legend) * 1.5)}; }

}  // namespace

cv::Size legend_size(const std::vector<LegendEntry>& entries, const Style& st) {
  const LegendMetrics m = legend_metrics(st);
  int text_w = 0;
  for (const auto& e : entries) text_w = std::max(text_w, measure(e.label, st.legend).width);
  return {2 * st.gap + m.sample + st.gap + text_w, 2 * st.gap + m.row * int(entries.size())};
}

void draw_bound_marker(cv::Mat& img, cv::Point2d c, double r, const cv::Scalar& colour, int thickness) {
  const double h = r * std::sqrt(3.0) / 2.0;  // half the side
  const std::vector<cv::Point> tri{fixed_point(c + cv::Point2d(0, -r)), fixed_point(c + cv::Point2d(h, r / 2)),
                                   fixed_point(c + cv::Point2d(-h, r / 2))};
  cv::polylines(img, tri, true, colour, thickness, cv::LINE_AA, kShift);
}

void draw_legend_at(cv::Mat& img, cv::Point tl, const std::vector<LegendEntry>& entries, const Style& st) {
  if (entries.empty()) return;
  const LegendMetrics m = legend_metrics(st);
  const cv::Rect rect(tl, legend_size(entries, st));
  cv::rectangle(img, rect, kWhite, cv::FILLED);
  cv::rectangle(img, rect, kLegendBorder, 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& e = entries[i];
    const double cy = rect.y + st.gap + m.row * (i + 0.5);
    const double x0 = rect.x + st.gap, x1 = x0 + m.sample;
    if (e.swatch == Swatch::bound) {
      draw_bound_marker(img, {(x0 + x1) / 2, cy}, m.row * 0.32, e.stroke.colour, std::max(2, e.stroke.thickness));
      put_text(img, e.label, {int(x1) + st.gap, int(std::lround(cy))}, HAlign::left, VAlign::middle, st.legend, kTextColour);
      continue;
    }
    if (e.swatch != Swatch::line) {  // box from 20 % to 80 % of the row
      const double h = m.row * 0.6;
      const cv::Rect box(cv::Point(int(x0), int(std::lround(cy - h / 2))),
                         cv::Point(int(x1), int(std::lround(cy + h / 2))));
      cv::rectangle(img, box, mix(kWhite, e.stroke.colour, e.alpha), cv::FILLED);
    }
    if (e.swatch != Swatch::box) {
      Stroke k = e.stroke;
      k.thickness = std::min(k.thickness, st.px(4));
      draw_stroke(img, {{x0 + k.thickness / 2.0, cy}, {x1 - k.thickness / 2.0, cy}}, k, st);
    }
    put_text(img, e.label, {int(x1) + st.gap, int(std::lround(cy))}, HAlign::left, VAlign::middle, st.legend,
             kTextColour);
  }
}

void draw_legend(cv::Mat& img, const cv::Rect& area, const std::vector<LegendEntry>& entries, const Style& st) {
  if (entries.empty()) return;
  const cv::Size box = legend_size(entries, st);
  const int inset = st.px(10);
  // Candidate corners, preferred order on ties: top-right, top-left, bottom-right, bottom-left.
  const int l = area.x + inset, r = area.x + area.width - inset - box.width;
  const int t = area.y + inset, b = area.y + area.height - inset - box.height;
  const std::array<cv::Point, 4> corners{{{r, t}, {l, t}, {r, b}, {l, b}}};
  cv::Point best = corners[0];
  int best_ink = std::numeric_limits<int>::max();
  for (const auto& c : corners) {
    const int ink = ink_in(img, cv::Rect(c, box));
    if (ink < best_ink) best_ink = ink, best = c;
  }
  draw_legend_at(img, best, entries, st);
}

// ---------------------------------------------------------------- output

void write_atomically(const std::string& who, const std::string& path, const std::vector<uchar>& bytes) {
  try {
    AtomicFile tmp(path);
    tmp.write(std::string(bytes.begin(), bytes.end()));
    tmp.close();
    tmp.commit();
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(who + ": cannot write " + e.what());  // e names the file and the reason
  }
}

void write_png(const std::string& who, const cv::Mat& bgr_image, const std::string& path) {
  // libpng directly (not OpenCV's imgcodecs, whose libraries cost every command ~0.2 s to load):
  // 8-bit RGB rows from the BGR image, into memory, then written atomically.
  const auto fail = [&] { throw std::runtime_error(who + ": PNG encoding failed for '" + path + "'"); };
  if (bgr_image.type() != CV_8UC3 || bgr_image.empty()) fail();
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    fail();
  }
  std::vector<uchar> bytes;
  std::vector<png_bytep> rows(static_cast<std::size_t>(bgr_image.rows));
  for (int r = 0; r < bgr_image.rows; ++r) rows[static_cast<std::size_t>(r)] = const_cast<png_bytep>(bgr_image.ptr<uchar>(r));
  if (setjmp(png_jmpbuf(png))) {  // libpng's errors return here
    png_destroy_write_struct(&png, &info);
    fail();
  }
  png_set_write_fn(
      png, &bytes,
      [](png_structp p, png_bytep data, png_size_t n) {
        auto* out = static_cast<std::vector<uchar>*>(png_get_io_ptr(p));
        out->insert(out->end(), data, data + n);
      },
      nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(bgr_image.cols), static_cast<png_uint_32>(bgr_image.rows), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_bgr(png);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  write_atomically(who, path, bytes);
}

std::vector<unsigned char> rgb_bytes(const cv::Mat& bgr_image) {
  cv::Mat rgb;
  cv::cvtColor(bgr_image, rgb, cv::COLOR_BGR2RGB);
  return {rgb.data, rgb.data + rgb.total() * rgb.elemSize()};
}

// ---------------------------------------------------------------- video

namespace {

struct Codec {
  const char* name;
  int api;
  const char* ext;  // container extension the writer needs; nullptr = the requested one
};

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower((unsigned char)c));
  return ext;
}

std::vector<Codec> codecs_for(const std::string& path) {
  const std::string ext = lower_extension(path);
  std::vector<Codec> out;
  if (ext == ".mp4" || ext == ".m4v" || ext == ".mov")
    out = {{"mp4v", cv::CAP_FFMPEG, nullptr}, {"avc1", cv::CAP_FFMPEG, nullptr}};
  out.push_back({"MJPG", cv::CAP_FFMPEG, ".avi"});
  out.push_back({"MJPG", cv::CAP_OPENCV_MJPEG, ".avi"});
  return out;
}

// The video writer module (plotting/video/video_module.cpp), loaded at the first video: next to the
// program, else where the build put it.
using WriteVideo = int (*)(const char*, int, int, double, int, int, int, const std::function<cv::Mat(int)>*, char*,
                           unsigned long);
WriteVideo video_writer(const std::string& who) {
  static const std::pair<WriteVideo, std::string> loaded = [] {
    std::string tried, why;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    for (const std::string& p : {ec ? std::string() : (exe.parent_path() / "libff_video.so").string(),
                                 std::string(FLEXFARM_VIDEO_MODULE)}) {
      if (p.empty() || !std::filesystem::exists(p)) continue;
      if (void* h = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL))
        if (void* f = dlsym(h, "ff_write_video")) return std::make_pair(reinterpret_cast<WriteVideo>(f), std::string());
      const char* e = dlerror();
      why = p + ": " + (e ? e : "no ff_write_video");
    }
    return std::make_pair(WriteVideo(nullptr), why.empty() ? std::string("libff_video.so not found next to the "
                                                                         "program or at " FLEXFARM_VIDEO_MODULE)
                                                            : why);
  }();
  if (!loaded.first) throw std::runtime_error(who + ": cannot load the video writer: " + loaded.second);
  return loaded.first;
}

}  // namespace

void write_video(const std::string& who, const std::string& path, double fps, cv::Size size, int frames,
                 const std::function<cv::Mat(int)>& frame) {
  const auto fail = [&](const std::string& why) { throw std::runtime_error(who + ": cannot write " + why); };
  try {
    AtomicFile probe(path);  // a temporary beside it can be made at all, before the module loads
  } catch (const std::runtime_error& e) {
    fail(e.what());
  }
  const WriteVideo write = video_writer(who);
  std::vector<std::string> tried;
  for (const Codec& c : codecs_for(path)) {
    // The encoder writes by name: into an exclusive temporary with the container's extension.
    AtomicFile tmp(path, c.ext ? c.ext : lower_extension(path));
    tmp.close();
    tried.push_back(c.name + std::string(c.api == cv::CAP_FFMPEG ? " (FFmpeg)" : " (OpenCV)"));
    const int fourcc = c.name[0] | c.name[1] << 8 | c.name[2] << 16 | c.name[3] << 24;  // VideoWriter::fourcc
    char why[512] = "";
    if (!write(tmp.path().c_str(), c.api, fourcc, fps, size.width, size.height, frames, &frame, why, sizeof why)) continue;
    std::error_code ec;
    if (std::filesystem::file_size(tmp.path(), ec) == 0 || ec) continue;
    try {
      tmp.commit();
    } catch (const std::runtime_error& e) {
      fail(e.what());
    }
    return;
  }
  std::string list;
  for (const auto& t : tried) list += (list.empty() ? "" : ", ") + t;
  fail(path + ": no video codec could be opened (tried " + list + ")");
}

}  // namespace ff::canvas
