// Line plots with OpenCV. The drawing pieces (palette use, Style, text, Axes, polylines, legend,
// atomic output) live in canvas.hpp and are shared with the charts and the arm animation.
#include "plotting/plot.hpp"

#include "plotting/canvas.hpp"

#include <array>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

namespace ff {
namespace {

using namespace canvas;

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

// ---------------------------------------------------------------- line plot

// Checks sizes and series lengths.
void validate(const LinePlot& p) {
  check_image_size("LinePlot", p.width, p.height);
  for (const auto& s : p.series)
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("LinePlot: series '" + s.label + "' has " + std::to_string(s.x.size()) +
                                  " x values but " + std::to_string(s.y.size()) + " y values");
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
  AxesOptions opt;
  if (!p.x_ticks.empty()) {
    double step = 1.0;
    for (std::size_t i = 1; i < p.x_ticks.size(); ++i) step = std::min(step, std::abs(p.x_ticks[i] - p.x_ticks[i - 1]));
    opt.x_ticks = Ticks{p.x_ticks, step, p.x_tick_labels};
  }
  return layout_axes({p.width, p.height}, x, y, axes_text(p), st, opt);
}

Stroke series_stroke(const Series& s, int colour, const Style& st) {
  return {bgr(palette_colour(colour)), st.px(s.width), s.dashed};
}

Stroke hline_stroke(const HLine& h, const Style& st) { return {kRefLineColour, st.px(1.5), h.dashed}; }

// A marker at every finite point of s inside the plot area: a dot, a cross, or a lower bound.
void draw_markers(cv::Mat& roi, const Axes& a, const Series& s, const Stroke& k, const Style& st) {
  if (s.marker == Series::Marker::kNone) return;
  const double r = 4.5 * st.s + k.thickness;  // px
  for (size_t i = 0; i < s.x.size(); ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
    const cv::Point2d c(a.ax(s.x[i]), a.ay(s.y[i]));
    if (c.x < -r || c.y < -r || c.x > roi.cols + r || c.y > roi.rows + r) continue;
    if (s.marker == Series::Marker::kDot) {
      cv::circle(roi, fixed_point(c), int(std::lround(r * 16)), k.colour, cv::FILLED, cv::LINE_AA, kShift);
    } else if (s.marker == Series::Marker::kBound) {
      draw_bound_marker(roi, c, 1.6 * r, k.colour, std::max(2, k.thickness));
    } else {
      for (double sgn : {-1.0, 1.0})
        cv::line(roi, fixed_point(c + cv::Point2d(-r, -sgn * r)), fixed_point(c + cv::Point2d(r, sgn * r)), k.colour,
                 std::max(2, k.thickness), cv::LINE_AA, kShift);
    }
  }
}

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
  std::vector<int> requested;
  for (const auto& s : p.series) requested.push_back(s.colour);
  const auto colours = assign_colours(requested);
  for (size_t i = 0; i < p.series.size(); ++i) {
    const Stroke k = series_stroke(p.series[i], colours[i], st);
    if (p.series[i].line) draw_series(roi, a, p.series[i].x, p.series[i].y, k, st);
    draw_markers(roi, a, p.series[i], k, st);
    const bool bound = !p.series[i].line && p.series[i].marker == Series::Marker::kBound;
    if (!p.series[i].label.empty()) legend.push_back({hershey_text(p.series[i].label), k, bound ? Swatch::bound : Swatch::line});
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
  return line_plot_axes(plot, style_for({plot.width, plot.height})).frame();
}

void render_line_plot(const LinePlot& plot, const std::string& png_path) {
  write_png("render_line_plot", render_bgr(plot), png_path);
}

std::vector<unsigned char> render_line_plot_rgb(const LinePlot& plot) { return rgb_bytes(render_bgr(plot)); }

}  // namespace ff
