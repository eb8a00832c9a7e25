// Line plots with OpenCV. Reusable pieces for later plot kinds (heat map, histogram, band, bar):
// palette, Style (sizes from the image size), text helpers, Axes (layout, data→pixel mapping,
// grid, frame, ticks, labels, title), polyline drawing (NaN breaks, clipping, dashes), legend.
#include "plotting/plot.hpp"

// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>

namespace ff {
namespace {

// ---------------------------------------------------------------- palette and fixed colours

// Okabe-Ito, reordered so the colours that read best on white come first; yellow last.
constexpr std::array<Rgb, 8> kPalette{{
    {0, 114, 178},    // blue
    {213, 94, 0},     // vermillion
    {0, 158, 115},    // bluish green
    {204, 121, 167},  // reddish purple
    {230, 159, 0},    // orange
    {86, 180, 233},   // sky blue
    {0, 0, 0},        // black
    {240, 228, 66},   // yellow
}};

cv::Scalar bgr(Rgb c) { return {double(c.b), double(c.g), double(c.r)}; }

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kTextColour(25, 25, 25);
const cv::Scalar kTickTextColour(55, 55, 55);
const cv::Scalar kFrameColour(70, 70, 70);
const cv::Scalar kGridColour(228, 228, 228);
const cv::Scalar kRefLineColour(120, 120, 120);
const cv::Scalar kLegendBorder(175, 175, 175);

// ---------------------------------------------------------------- nice ticks

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

// The next smaller 1-2-5 step.
NiceStep smaller(NiceStep s) {
  if (s.mantissa == 1) return {5, s.exponent - 1};
  return {s.mantissa == 5 ? 2 : 1, s.exponent};
}

// [lo, hi] ordered and widened when (nearly) empty, so ticks can always be placed.
std::pair<double, double> widened(double lo, double hi) {
  if (lo > hi) std::swap(lo, hi);
  const double mag = std::max(std::abs(lo), std::abs(hi));
  if (hi - lo > mag * 1e-12 && hi - lo > 0) return {lo, hi};
  const double half = mag > 0 ? mag * 0.1 : 1.0;
  return {lo - half, hi + half};
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

struct Ticks {
  std::vector<double> values;
  double step = 1;
};

// Ticks for [lo, hi]: the 1-2-5 step nearest range/(target-1), made smaller until two fit.
Ticks nice_ticks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi))
    throw std::invalid_argument("calc_nice_ticks: range must be finite");
  std::tie(lo, hi) = widened(lo, hi);
  if (!std::isfinite(hi - lo)) return {{lo, hi}, hi / 2 - lo / 2};
  NiceStep s = nice_step_near((hi - lo) / std::max(target - 1, 1));
  for (;;) {
    auto v = multiples_inside(lo, hi, s);
    if (v.size() >= 2) return {std::move(v), s.value()};
    s = smaller(s);
  }
}

// ---------------------------------------------------------------- text

// ASCII spellings of UTF-8 signs the Hershey font cannot draw.
constexpr std::array<std::pair<std::string_view, std::string_view>, 24> kAsciiFor{{
    {"\u00b7", "."},     {"\u00b1", "+/-"},   {"\u00b0", "deg"},   {"\u00b5", "u"},
    {"\u03bc", "u"},     {"\u00b2", "^2"},    {"\u00b3", "^3"},    {"\u00d7", "x"},
    {"\u2212", "-"},     {"\u2013", "-"},     {"\u2014", "-"},     {"\u00a0", " "},
    {"\u2009", " "},     {"\u202f", " "},     {"\u0394", "Delta"}, {"\u03b8", "theta"},
    {"\u03c9", "omega"}, {"\u03c4", "tau"},   {"\u03b1", "alpha"}, {"\u03c6", "phi"},
    {"\u03b6", "zeta"},  {"\u03c3", "sigma"}, {"\u03c0", "pi"},    {"\u2248", "~"},
}};

// `s` with every non-ASCII UTF-8 sequence replaced by its ASCII spelling, or '?'.
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

struct Font {
  double scale;
  int thickness;
};

constexpr int kFace = cv::FONT_HERSHEY_SIMPLEX;

// Size of `t`: width, height above the baseline, and depth below it.
struct TextSize {
  int width, ascent, descent;
  int height() const { return ascent + descent; }
};

TextSize measure(const std::string& t, const Font& f) {
  int base = 0;
  const cv::Size sz = cv::getTextSize(t, kFace, f.scale, f.thickness, &base);
  return {sz.width, sz.height, base};
}

// Height of a line of text with capitals and descenders in font `f`.
int line_height(const Font& f) { return measure("Ag(", f).height(); }

// `f` scaled down if needed so `t` fits into `max_width` px.
Font fitted(const std::string& t, Font f, int max_width) {
  const int w = measure(t, f).width;
  if (w > max_width && w > 0) f.scale *= double(max_width) / w;
  return f;
}

enum class HAlign { left, centre, right };
enum class VAlign { top, middle, bottom };  // top of capitals, middle of capitals, bottom of descenders

// Draws ASCII text `t` anti-aliased, aligned to the point `at`.
void put_text(cv::Mat& img, const std::string& t, cv::Point at, HAlign h, VAlign v, const Font& f,
              const cv::Scalar& colour) {
  const TextSize ts = measure(t, f);
  const int x = h == HAlign::left ? at.x : h == HAlign::centre ? at.x - ts.width / 2 : at.x - ts.width;
  const int y = v == VAlign::top ? at.y + ts.ascent : v == VAlign::middle ? at.y + ts.ascent / 2 : at.y - ts.descent;
  cv::putText(img, t, {x, y}, kFace, f.scale, colour, f.thickness, cv::LINE_AA);
}

// `t` drawn on a white patch and turned 90° counter-clockwise (reads bottom to top).
cv::Mat rotated_text(const std::string& t, const Font& f, const cv::Scalar& colour) {
  const TextSize ts = measure(t, f);
  cv::Mat patch(ts.height() + 2, ts.width + 2, CV_8UC3, kWhite);
  put_text(patch, t, {1, 1}, HAlign::left, VAlign::top, f, colour);
  cv::Mat turned;
  cv::rotate(patch, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
  return turned;
}

// Copies `patch` into `img` with its top-left at `tl`, cut to the image.
void paste(cv::Mat& img, const cv::Mat& patch, cv::Point tl) {
  const cv::Rect dst = cv::Rect(tl, patch.size()) & cv::Rect({0, 0}, img.size());
  if (dst.empty()) return;
  patch(cv::Rect(dst.tl() - tl, dst.size())).copyTo(img(dst));
}

// ---------------------------------------------------------------- style

// Sizes derived from the image size; everything is designed at 1400 × 800 (factor s = 1).
struct Style {
  double s;
  Font title, label, tick, legend;
  int pad, gap, tick_len;
  int px(double at_reference) const { return std::max(1, int(std::lround(at_reference * s))); }
};

Style style_for(cv::Size size) {
  const double s = std::clamp(std::min(size.width / 1400.0, size.height / 800.0), 0.6, 4.0);
  const int thin = std::max(1, int(std::lround(s))), bold = s < 0.7 ? 1 : std::max(2, int(std::lround(2 * s)));
  return {s, {1.0 * s, bold}, {0.75 * s, thin}, {0.62 * s, thin}, {0.62 * s, thin},
          int(std::lround(16 * s)), int(std::lround(9 * s)), int(std::lround(7 * s))};
}

// ---------------------------------------------------------------- axes

struct Range {
  double lo, hi;
};

struct AxesText {
  std::string title, x_label, y_label;  // already ASCII
};

// A 2-D axes box: plot area in image pixels, the data range it shows and the ticks.
struct Axes {
  cv::Rect area;
  Range x, y;
  Ticks x_ticks, y_ticks;
  // Data → pixel inside the area (0 = first column/row of the area).
  double ax(double v) const { return (v - x.lo) / (x.hi - x.lo) * (area.width - 1); }
  double ay(double v) const { return (y.hi - v) / (y.hi - y.lo) * (area.height - 1); }
  // Data → image pixel.
  int ix(double v) const { return area.x + int(std::lround(ax(v))); }
  int iy(double v) const { return area.y + int(std::lround(ay(v))); }
};

// Widest tick label of `t`.
int widest_label(const Ticks& t, const Font& f) {
  int w = 0;
  for (double v : t.values) w = std::max(w, measure(format_tick(v, t.step), f).width);
  return w;
}

// Y ticks about every 90 px of area height.
Ticks y_ticks_for(Range y, int area_height, double s) {
  return nice_ticks(y.lo, y.hi, std::clamp(int(area_height / (90 * s)), 3, 10));
}

// X ticks about every 140 px, fewer while neighbouring labels would come closer than 2 gaps.
Ticks x_ticks_for(Range x, int area_width, const Style& st) {
  for (int target = std::clamp(int(area_width / (140 * st.s)), 3, 12);; --target) {
    Ticks t = nice_ticks(x.lo, x.hi, target);
    const double spacing = t.step / (x.hi - x.lo) * area_width;
    if (target <= 2 || spacing >= widest_label(t, st.tick) + 3 * st.gap) return t;
  }
}

// Margins from the text sizes, then ticks for the area that is left.
Axes layout_axes(cv::Size img, Range x, Range y, const AxesText& text, const Style& st) {
  const int tick_h = measure("0", st.tick).ascent;
  const int top = st.pad + std::max(text.title.empty() ? 0 : line_height(st.title) + st.gap, tick_h);
  const int bottom = st.tick_len + st.gap + tick_h + st.pad +
                     (text.x_label.empty() ? 0 : st.gap + line_height(st.label));
  const int area_h = std::max(10, img.height - top - bottom);
  Ticks yt = y_ticks_for(y, area_h, st.s);
  const int left = st.pad + (text.y_label.empty() ? 0 : line_height(st.label) + st.gap) +
                   widest_label(yt, st.tick) + st.gap + st.tick_len;
  // Right margin leaves room for half of the last x label; two passes since ticks depend on width.
  int right = st.pad;
  Ticks xt = x_ticks_for(x, std::max(10, img.width - left - right), st);
  right = std::max(st.pad, widest_label(xt, st.tick) / 2 + st.gap);
  xt = x_ticks_for(x, std::max(10, img.width - left - right), st);
  const cv::Rect area(left, top, std::max(10, img.width - left - right), area_h);
  return {area, x, y, std::move(xt), std::move(yt)};
}

// Light grid lines at every tick.
void draw_grid(cv::Mat& img, const Axes& a) {
  const int x0 = a.area.x, x1 = a.area.x + a.area.width - 1;
  const int y0 = a.area.y, y1 = a.area.y + a.area.height - 1;
  for (double v : a.x_ticks.values) cv::line(img, {a.ix(v), y0}, {a.ix(v), y1}, kGridColour, 1);
  for (double v : a.y_ticks.values) cv::line(img, {x0, a.iy(v)}, {x1, a.iy(v)}, kGridColour, 1);
}

// Frame one pixel outside the area, outward ticks and their labels.
void draw_frame_and_ticks(cv::Mat& img, const Axes& a, const Style& st) {
  const cv::Rect& r = a.area;
  cv::rectangle(img, {r.x - 1, r.y - 1}, {r.x + r.width, r.y + r.height}, kFrameColour, 1);
  const int below = r.y + r.height, left = r.x - 1;
  // X ticks and labels, kept inside the image at the ends.
  for (double v : a.x_ticks.values) {
    const int X = a.ix(v);
    cv::line(img, {X, below}, {X, below + st.tick_len}, kFrameColour, 1);
    const std::string t = format_tick(v, a.x_ticks.step);
    const int half = measure(t, st.tick).width / 2;
    const int cx = std::clamp(X, half + 2, img.cols - half - 2);
    put_text(img, t, {cx, below + st.tick_len + st.gap}, HAlign::centre, VAlign::top, st.tick, kTickTextColour);
  }
  // Y ticks and labels, right-aligned against the ticks.
  for (double v : a.y_ticks.values) {
    const int Y = a.iy(v);
    cv::line(img, {left - st.tick_len, Y}, {left, Y}, kFrameColour, 1);
    put_text(img, format_tick(v, a.y_ticks.step), {left - st.tick_len - st.gap, Y}, HAlign::right,
             VAlign::middle, st.tick, kTickTextColour);
  }
}

// X label centred under the tick labels; y label rotated, centred left of them; title on top.
void draw_axes_text(cv::Mat& img, const Axes& a, const AxesText& text, const Style& st) {
  const cv::Rect& r = a.area;
  if (!text.x_label.empty()) {
    const Font f = fitted(text.x_label, st.label, img.cols - 2 * st.pad);
    const int cx = std::clamp(r.x + r.width / 2, measure(text.x_label, f).width / 2 + st.pad,
                              img.cols - measure(text.x_label, f).width / 2 - st.pad);
    put_text(img, text.x_label, {cx, img.rows - st.pad}, HAlign::centre, VAlign::bottom, f, kTextColour);
  }
  if (!text.y_label.empty()) {
    const cv::Mat patch = rotated_text(text.y_label, fitted(text.y_label, st.label, img.rows - 2 * st.pad), kTextColour);
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

using Polyline = std::vector<cv::Point2d>;

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

// Pixel-space pieces of a series: split at NaN/inf and where segments leave `clip`.
// An isolated finite point becomes a one-point piece.
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

constexpr int kShift = 4;  // sub-pixel bits for OpenCV drawing
cv::Point fixed_point(cv::Point2d p) { return {int(std::lround(p.x * 16)), int(std::lround(p.y * 16))}; }

// Solid anti-aliased polyline, or a dot for a one-point piece.
void draw_solid(cv::Mat& img, const Polyline& pl, const cv::Scalar& c, int th) {
  if (pl.size() == 1) {
    cv::circle(img, fixed_point(pl[0]), std::max(2, th) * 16, c, cv::FILLED, cv::LINE_AA, kShift);
    return;
  }
  std::vector<cv::Point> pts;
  for (const auto& p : pl) pts.push_back(fixed_point(p));
  cv::polylines(img, pts, false, c, th, cv::LINE_AA, kShift);
}

// Dashed polyline: `on` px drawn, `off` px skipped, the pattern running on across vertices.
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

// Line style shared by plot lines and legend samples.
struct Stroke {
  cv::Scalar colour;
  int thickness;
  bool dashed;
};

// Dash and gap lengths for a stroke; the gap allows for the round caps.
std::pair<double, double> dash_pattern(const Stroke& k, const Style& st) {
  return {12 * st.s + k.thickness, 7 * st.s + k.thickness};
}

void draw_stroke(cv::Mat& img, const Polyline& pl, const Stroke& k, const Style& st) {
  if (!k.dashed) return draw_solid(img, pl, k.colour, k.thickness);
  const auto [on, off] = dash_pattern(k, st);
  draw_dashed(img, pl, k.colour, k.thickness, on, off);
}

// Draws a series into `roi` (the plot area), clipped to it.
void draw_series(cv::Mat& roi, const Axes& a, const std::vector<double>& x, const std::vector<double>& y,
                 const Stroke& k, const Style& st) {
  const double m = 4.0 * k.thickness + 4;  // clip a little outside so caps at the edge look right
  const cv::Rect2d clip(-m, -m, roi.cols + 2 * m, roi.rows + 2 * m);
  for (const auto& pl : pieces(x, y, a, clip)) draw_stroke(roi, pl, k, st);
}

// ---------------------------------------------------------------- legend

struct LegendEntry {
  std::string label;  // ASCII
  Stroke stroke;
};

// Number of "ink" pixels (darker than the grid) in `r` of `img`.
int ink_in(const cv::Mat& img, const cv::Rect& r) {
  cv::Mat grey;
  cv::cvtColor(img(r & cv::Rect({0, 0}, img.size())), grey, cv::COLOR_BGR2GRAY);
  return cv::countNonZero(grey < 200);
}

// Legend box in the corner of the area that covers the least drawn data; entries top to bottom.
void draw_legend(cv::Mat& img, const cv::Rect& area, const std::vector<LegendEntry>& entries, const Style& st) {
  if (entries.empty()) return;
  const int sample = st.px(40), row = int(line_height(st.legend) * 1.5), inset = st.px(10);
  int text_w = 0;
  for (const auto& e : entries) text_w = std::max(text_w, measure(e.label, st.legend).width);
  const cv::Size box(2 * st.gap + sample + st.gap + text_w, 2 * st.gap + row * int(entries.size()));
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
  // Box, then one row per entry: a line sample and the label.
  const cv::Rect rect(best, box);
  cv::rectangle(img, rect, kWhite, cv::FILLED);
  cv::rectangle(img, rect, kLegendBorder, 1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const double cy = rect.y + st.gap + row * (i + 0.5);
    const double x0 = rect.x + st.gap, x1 = x0 + sample;
    Stroke k = entries[i].stroke;
    k.thickness = std::min(k.thickness, st.px(4));
    draw_stroke(img, {{x0 + k.thickness / 2.0, cy}, {x1 - k.thickness / 2.0, cy}}, k, st);
    put_text(img, entries[i].label, {int(x1) + st.gap, int(std::lround(cy))}, HAlign::left, VAlign::middle,
             st.legend, kTextColour);
  }
}

// ---------------------------------------------------------------- line plot

// Checks sizes and series lengths.
void validate(const LinePlot& p) {
  if (p.width < 320 || p.height < 240 || p.width > 20000 || p.height > 20000)
    throw std::invalid_argument("LinePlot: size " + std::to_string(p.width) + "x" + std::to_string(p.height) +
                                " outside 320x240 .. 20000x20000");
  for (const auto& s : p.series)
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("LinePlot: series '" + s.label + "' has " + std::to_string(s.x.size()) +
                                  " x values but " + std::to_string(s.y.size()) + " y values");
}

// Axis range: fixed ends where given, else the data extent (lo/hi; NaN if none) plus 4 %.
Range resolve_range(double fixed_lo, double fixed_hi, double data_lo, double data_hi) {
  if (!std::isfinite(data_lo)) data_lo = std::isfinite(fixed_lo) ? fixed_lo : 0.0;
  if (!std::isfinite(data_hi)) data_hi = std::isfinite(fixed_hi) ? fixed_hi : 1.0;
  auto [lo, hi] = widened(data_lo, data_hi);
  const double margin = 0.04 * (hi - lo);
  lo = std::isfinite(fixed_lo) ? fixed_lo : lo - margin;
  hi = std::isfinite(fixed_hi) ? fixed_hi : hi + margin;
  std::tie(lo, hi) = widened(lo, hi);
  return {lo, hi};
}

// Extent of the finite values of `v` selected by `keep(i)`, folded into [lo, hi].
template <class Keep>
void extend(double& lo, double& hi, const std::vector<double>& v, Keep keep) {
  for (size_t i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && keep(i)) lo = std::min(lo, v[i]), hi = std::max(hi, v[i]);
}

// X range from all finite points, y range from the points inside the x range and the h-lines.
std::pair<Range, Range> data_ranges(const LinePlot& p) {
  const double inf = std::numeric_limits<double>::infinity();
  double xlo = inf, xhi = -inf, ylo = inf, yhi = -inf;
  for (const auto& s : p.series) extend(xlo, xhi, s.x, [&](size_t i) { return std::isfinite(s.y[i]); });
  const Range x = resolve_range(p.x_min, p.x_max, xlo <= xhi ? xlo : NAN, xlo <= xhi ? xhi : NAN);
  for (const auto& s : p.series)
    extend(ylo, yhi, s.y, [&](size_t i) { return s.x[i] >= x.lo && s.x[i] <= x.hi; });
  for (const auto& h : p.hlines)
    if (std::isfinite(h.y)) ylo = std::min(ylo, h.y), yhi = std::max(yhi, h.y);
  const Range y = resolve_range(p.y_min, p.y_max, ylo <= yhi ? ylo : NAN, ylo <= yhi ? yhi : NAN);
  return {x, y};
}

AxesText axes_text(const LinePlot& p) {
  return {hershey_text(p.title), hershey_text(p.x_label), hershey_text(p.y_label)};
}

Axes line_plot_axes(const LinePlot& p, const Style& st) {
  const auto [x, y] = data_ranges(p);
  return layout_axes({p.width, p.height}, x, y, axes_text(p), st);
}

// Palette index per series: explicit ones as given, -1 takes the next index no series claims.
std::vector<int> series_colours(const std::vector<Series>& series) {
  std::vector<bool> taken(kPalette.size(), false);
  for (const auto& s : series)
    if (s.colour >= 0) taken[s.colour % kPalette.size()] = true;
  std::vector<int> out;
  size_t next = 0, auto_count = 0;
  for (const auto& s : series) {
    if (s.colour >= 0) { out.push_back(s.colour); continue; }
    while (next < taken.size() && taken[next]) ++next;
    out.push_back(next < taken.size() ? int(next++) : int(auto_count % kPalette.size()));
    ++auto_count;
  }
  return out;
}

Stroke series_stroke(const Series& s, int colour, const Style& st) {
  return {bgr(palette_colour(colour)), st.px(s.width), s.dashed};
}

Stroke hline_stroke(const HLine& h, const Style& st) { return {kRefLineColour, st.px(1.5), h.dashed}; }

// Draws h-lines and series into the plot area; returns the legend entries in drawing order.
std::vector<LegendEntry> draw_line_data(cv::Mat& img, const Axes& a, const LinePlot& p, const Style& st) {
  cv::Mat roi = img(a.area);
  std::vector<LegendEntry> legend;
  for (const auto& h : p.hlines) {
    if (!std::isfinite(h.y)) continue;
    const Stroke k = hline_stroke(h, st);
    const double y = a.ay(h.y);
    if (y > -k.thickness && y < roi.rows + k.thickness) draw_stroke(roi, {{0, y}, {roi.cols - 1.0, y}}, k, st);
  }
  const auto colours = series_colours(p.series);
  for (size_t i = 0; i < p.series.size(); ++i) {
    const Stroke k = series_stroke(p.series[i], colours[i], st);
    draw_series(roi, a, p.series[i].x, p.series[i].y, k, st);
    if (!p.series[i].label.empty()) legend.push_back({hershey_text(p.series[i].label), k});
  }
  for (const auto& h : p.hlines)
    if (!h.label.empty()) legend.push_back({hershey_text(h.label), hline_stroke(h, st)});
  return legend;
}

// The whole line plot as a BGR image.
cv::Mat render_bgr(const LinePlot& p) {
  validate(p);
  const Style st = style_for({p.width, p.height});
  const Axes a = line_plot_axes(p, st);
  cv::Mat img(p.height, p.width, CV_8UC3, kWhite);
  draw_grid(img, a);
  const auto legend = draw_line_data(img, a, p, st);
  draw_frame_and_ticks(img, a, st);
  draw_axes_text(img, a, axes_text(p), st);
  draw_legend(img, a.area, legend, st);
  return img;
}

// ---------------------------------------------------------------- output

// Writes `bytes` to "<path>.tmp" and renames it to `path`; throws naming `path` on failure.
void write_atomically(const std::string& path, const std::vector<uchar>& bytes) {
  const std::string tmp = path + ".tmp";
  const auto fail = [&](const std::string& why) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw std::runtime_error("render_line_plot: cannot write '" + path + "': " + why);
  };
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) fail(std::generic_category().message(errno));
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    f.close();
    if (!f) fail("write to '" + tmp + "' failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.message());
}

}  // namespace

// ---------------------------------------------------------------- public API

Rgb palette_colour(int i) {
  const int n = int(kPalette.size());
  return kPalette[size_t(((i % n) + n) % n)];
}

int palette_size() { return int(kPalette.size()); }

std::vector<double> calc_nice_ticks(double lo, double hi, int target) { return nice_ticks(lo, hi, target).values; }

double nice_tick_step(double lo, double hi, int target) { return nice_ticks(lo, hi, target).step; }

std::string format_tick(double value, double step) {
  // Number of decimals that shows multiples of x exactly (up to 15).
  const auto decimals = [](double x) {
    for (int d = 0; d < 15; ++d) {
      const double scaled = x * std::pow(10.0, d);
      if (std::abs(scaled - std::round(scaled)) < 1e-6 * std::max(1.0, scaled)) return d;
    }
    return 15;
  };
  if (!std::isfinite(value)) return std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf";
  step = std::abs(step);
  char buf[64];
  if (!std::isfinite(step) || step == 0) {  // no step known: shortest general form
    std::snprintf(buf, sizeof buf, "%.6g", value);
    return buf;
  }
  if (std::abs(value) < step * 1e-6) return "0";
  if (step >= 1e5 || step < 1e-4) {  // exponent form, digits down to the step
    const int es = int(std::floor(std::log10(step) + 1e-9));
    const int ev = int(std::floor(std::log10(std::abs(value)) + 1e-9));
    const int digits = std::max(0, ev - es + decimals(step / std::pow(10.0, es)));
    std::snprintf(buf, sizeof buf, "%.*e", digits, value);
  } else {
    std::snprintf(buf, sizeof buf, "%.*f", decimals(step), value);
  }
  return buf;
}

PlotFrame line_plot_frame(const LinePlot& plot) {
  validate(plot);
  const Axes a = line_plot_axes(plot, style_for({plot.width, plot.height}));
  return {a.area.x, a.area.y, a.area.width, a.area.height, a.x.lo, a.x.hi, a.y.lo, a.y.hi};
}

void render_line_plot(const LinePlot& plot, const std::string& png_path) {
  std::vector<uchar> png;
  if (!cv::imencode(".png", render_bgr(plot), png))
    throw std::runtime_error("render_line_plot: PNG encoding failed for '" + png_path + "'");
  write_atomically(png_path, png);
}

std::vector<unsigned char> render_line_plot_rgb(const LinePlot& plot) {
  cv::Mat rgb;
  cv::cvtColor(render_bgr(plot), rgb, cv::COLOR_BGR2RGB);
  return {rgb.data, rgb.data + rgb.total() * rgb.elemSize()};
}

}  // namespace ff
