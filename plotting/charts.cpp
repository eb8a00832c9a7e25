// Heat map, band plot, histogram, CDF and bar chart, drawn with the shared pieces of canvas.hpp.
#include "plotting/charts.hpp"

#include "plotting/canvas.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

namespace ff {
namespace {

using namespace canvas;

constexpr double kInf = std::numeric_limits<double>::infinity();

constexpr Bgr kNanFill{200, 200, 200};
constexpr Bgr kNanHatch{150, 150, 150};

// ---------------------------------------------------------------- shared

ChartImage chart_image(const cv::Mat& img, const Axes& a) {
  ChartImage out;
  out.width = img.cols, out.height = img.rows;
  out.rgb = rgb_bytes(img);
  out.frame = a.frame();
  return out;
}

// Compact number text: 3 significant digits, whole numbers from 1000 to 1e6 in full.
std::string format_value(double v, int digits = 3) {
  if (std::isnan(v)) return "n/a";
  char buf[64];
  if (std::abs(v) >= 1000 && std::abs(v) < 1e6) std::snprintf(buf, sizeof buf, "%.0f", v);
  else std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

// Count of finite values.
size_t finite_count(const std::vector<double>& v) {
  return size_t(std::count_if(v.begin(), v.end(), [](double x) { return std::isfinite(x); }));
}

// Vertical dashed marker lines across the area, colours palette 1, 2, ...; legend entries for labelled ones.
std::vector<LegendEntry> draw_markers(cv::Mat& img, const Axes& a, const Histogram& h, const Style& st) {
  std::vector<LegendEntry> legend;
  cv::Mat roi = img(a.area);
  for (size_t i = 0; i < h.markers.size(); ++i) {
    const Stroke k{bgr(palette_colour(int(i) + 1)), st.px(2.5), true};
    const double x = a.ax(h.markers[i]);
    if (std::isfinite(x) && x > -k.thickness && x < roi.cols + k.thickness)
      draw_stroke(roi, {{x, 0}, {x, roi.rows - 1.0}}, k, st);
    if (i < h.marker_labels.size() && !h.marker_labels[i].empty())
      legend.push_back({hershey_text(h.marker_labels[i]), k});
  }
  return legend;
}

// ---------------------------------------------------------------- heat map

const std::array<Rgb, 256>& viridis_table() {
  static const std::array<Rgb, 256> table = [] {
    cv::Mat ramp(1, 256, CV_8UC1), coloured;
    for (int i = 0; i < 256; ++i) ramp.at<uchar>(0, i) = uchar(i);
    cv::applyColorMap(ramp, coloured, cv::COLORMAP_VIRIDIS);
    std::array<Rgb, 256> t{};
    for (int i = 0; i < 256; ++i) {
      const auto c = coloured.at<cv::Vec3b>(0, i);  // BGR
      t[size_t(i)] = {c[2], c[1], c[0]};
    }
    return t;
  }();
  return table;
}

void validate(const HeatMap& m) {
  check_image_size("HeatMap", m.width, m.height);
  if (m.x.empty() || m.y.empty())
    throw std::invalid_argument("HeatMap: needs at least one cell centre in x and in y");
  if (m.values.size() != m.x.size() * m.y.size())
    throw std::invalid_argument("HeatMap: " + std::to_string(m.values.size()) + " values for " +
                                std::to_string(m.y.size()) + " x " + std::to_string(m.x.size()) + " cells");
  if (!m.bounds.empty() && m.bounds.size() != m.values.size())
    throw std::invalid_argument("HeatMap: " + std::to_string(m.bounds.size()) + " bound flags for " +
                                std::to_string(m.values.size()) + " values");
}

// Fills `cell` grey with diagonal hatching (for NaN).
void hatch(cv::Mat& img, const cv::Rect& cell, const Style& st) {
  const cv::Rect r = cell & cv::Rect({0, 0}, img.size());
  if (r.empty()) return;
  cv::Mat roi = img(r);
  roi.setTo(cv::Scalar(kNanFill));
  const int step = st.px(9);
  for (int k = -roi.rows; k < roi.cols; k += step)
    cv::line(roi, {k, roi.rows}, {k + roi.rows, 0}, kNanHatch, 1, cv::LINE_AA);
}

// Text colour readable on `c`.
cv::Scalar text_on(const cv::Scalar& c) {
  const double luminance = 0.114 * c[0] + 0.587 * c[1] + 0.299 * c[2];
  return luminance > 120 ? kTextColour : kWhite;
}

struct HeatLayout {
  Axes axes;
  Range values;     // colour bar range
  Ticks bar_ticks;
  bool has_nan;
  int bar_w;
};

// Cell index ticks labelled with the cell centres.
Ticks centre_ticks(const std::vector<double>& centres) {
  Ticks t;
  t.step = 1;
  for (size_t i = 0; i < centres.size(); ++i)
    t.values.push_back(double(i)), t.labels.push_back(format_value(centres[i], 4));
  return t;
}

HeatLayout heat_layout(const HeatMap& m, const Style& st) {
  double lo = kInf, hi = -kInf;
  extend(lo, hi, m.values);
  const bool has_nan = finite_count(m.values) < m.values.size();
  Range values{0, 1};
  if (lo <= hi) std::tie(values.lo, values.hi) = widened(lo, hi);
  Ticks bar_ticks = nice_ticks(values.lo, values.hi, std::clamp(int(m.height / (110 * st.s)), 3, 8));
  int tick_w = has_nan ? measure("n/a", st.tick).width : 0;
  for (size_t i = 0; i < bar_ticks.values.size(); ++i)
    tick_w = std::max(tick_w, measure(bar_ticks.label(i), st.tick).width);
  const int bar_w = st.px(26);
  const std::string value_label = hershey_text(m.value_label);
  const int reserve = 3 * st.gap + bar_w + st.tick_len + st.gap + tick_w +
                      (value_label.empty() ? 0 : 2 * st.gap + line_height(st.label));
  AxesOptions opt;
  opt.x_ticks = centre_ticks(m.x);
  opt.y_ticks = centre_ticks(m.y);
  opt.reserve_right = reserve;
  const Range x{-0.5, double(m.x.size()) - 0.5}, y{-0.5, double(m.y.size()) - 0.5};
  const AxesText text{hershey_text(m.title), hershey_text(m.x_label), hershey_text(m.y_label)};
  return {layout_axes({m.width, m.height}, x, y, text, st, opt), values, std::move(bar_ticks), has_nan, bar_w};
}

// Pixel rectangle of cell (ix, iy); neighbours share no pixels and together cover the area.
cv::Rect cell_rect(const Axes& a, size_t ix, size_t iy) {
  const auto col = [&](double v) {
    return a.area.x + int(std::lround((v - a.x.lo) / (a.x.hi - a.x.lo) * a.area.width));
  };
  const auto row = [&](double v) {
    return a.area.y + int(std::lround((a.y.hi - v) / (a.y.hi - a.y.lo) * a.area.height));
  };
  return cv::Rect(cv::Point(col(ix - 0.5), row(iy + 0.5)), cv::Point(col(ix + 0.5), row(iy - 0.5)));
}

// Font for the cell annotations, or none if the texts do not fit the cells.
std::optional<Font> annotation_font(const HeatMap& m, const Axes& a, const Style& st) {
  const cv::Rect c = cell_rect(a, 0, 0);
  int widest = 0;
  for (double v : m.values) widest = std::max(widest, measure((m.bounds.empty() ? "" : "> ") + format_value(v), st.tick).width);
  for (double f : {1.2, 1.0, 0.85, 0.7}) {
    const Font font{st.tick.scale * f, st.tick.thickness};
    if (widest * f <= c.width - 2 * st.px(5) && measure("0", font).ascent <= c.height * 0.45) return font;
  }
  return std::nullopt;
}

PlotFrame draw_colour_bar(cv::Mat& img, const HeatLayout& L, const HeatMap& m, const Style& st) {
  const cv::Rect& area = L.axes.area;
  const int left = area.x + area.width + 3 * st.gap;
  const int swatch = st.px(24);
  const int top = area.y, bottom = area.y + area.height - 1 - (L.has_nan ? swatch + 2 * st.gap : 0);
  const int height = bottom - top + 1;
  for (int r = top; r <= bottom; ++r) {
    const Rgb c = viridis_colour(height > 1 ? double(bottom - r) / (height - 1) : 0.5);
    cv::line(img, {left, r}, {left + L.bar_w - 1, r}, bgr(c), 1);
  }
  cv::rectangle(img, {left - 1, top - 1}, {left + L.bar_w, bottom + 1}, kFrameColour, 1);
  const PlotFrame bar{left, top, L.bar_w, height, 0, 1, L.values.lo, L.values.hi};
  const int tick_x = left + L.bar_w;
  int label_right = tick_x;
  for (size_t i = 0; i < L.bar_ticks.values.size(); ++i) {
    const int Y = int(std::lround(bar.y_to_px(L.bar_ticks.values[i])));
    cv::line(img, {tick_x, Y}, {tick_x + st.tick_len, Y}, kFrameColour, 1);
    const std::string t = L.bar_ticks.label(i);
    put_text(img, t, {tick_x + st.tick_len + st.gap, Y}, HAlign::left, VAlign::middle, st.tick, kTickTextColour);
    label_right = std::max(label_right, tick_x + st.tick_len + st.gap + measure(t, st.tick).width);
  }
  if (L.has_nan) {
    const cv::Rect sw(left, area.y + area.height - swatch, L.bar_w, swatch);
    hatch(img, sw, st);
    cv::rectangle(img, {sw.x - 1, sw.y - 1}, {sw.x + sw.width, sw.y + sw.height}, kFrameColour, 1);
    put_text(img, "n/a", {tick_x + st.tick_len + st.gap, sw.y + sw.height / 2}, HAlign::left, VAlign::middle, st.tick,
             kTickTextColour);
    label_right = std::max(label_right, tick_x + st.tick_len + st.gap + measure("n/a", st.tick).width);
  }
  const std::string value_label = hershey_text(m.value_label);
  if (!value_label.empty()) {
    const cv::Mat patch = rotated_text(value_label, fitted(value_label, st.label, height), kTextColour);
    paste(img, patch, {label_right + 2 * st.gap, top + height / 2 - patch.rows / 2});
  }
  return bar;
}

cv::Mat heat_map_bgr(const HeatMap& m, ChartImage* info) {
  validate(m);
  const Style st = style_for({m.width, m.height});
  const HeatLayout L = heat_layout(m, st);
  const Axes& a = L.axes;
  cv::Mat img(m.height, m.width, CV_8UC3, kWhite);
  const size_t nx = m.x.size(), ny = m.y.size();
  const std::optional<Font> font = m.annotate ? annotation_font(m, a, st) : std::nullopt;
  const bool separators = std::min(cell_rect(a, 0, 0).width, cell_rect(a, 0, 0).height) >= st.px(40);
  for (size_t iy = 0; iy < ny; ++iy)
    for (size_t ix = 0; ix < nx; ++ix) {
      const double v = m.values[iy * nx + ix];
      const cv::Rect r = cell_rect(a, ix, iy);
      if (!std::isfinite(v)) { hatch(img, r, st); continue; }
      const cv::Scalar c = bgr(viridis_colour((v - L.values.lo) / (L.values.hi - L.values.lo)));
      cv::rectangle(img, r, c, cv::FILLED);
      const bool bound = !m.bounds.empty() && m.bounds[iy * nx + ix];
      if (font)
        put_text(img, (bound ? "> " : "") + format_value(v), (r.tl() + r.br()) / 2, HAlign::centre, VAlign::middle,
                 *font, text_on(c));
      if (bound) {  // in the top-right corner, so it shows when the cells are too small for text
        const double rad = std::min(r.width, r.height) * 0.12;
        draw_bound_marker(img, {r.x + r.width - 1.6 * rad, r.y + 1.6 * rad}, rad, text_on(c), std::max(1, st.px(2)));
      }
    }
  if (separators) {  // thin white lines between cells
    for (size_t ix = 1; ix < nx; ++ix) {
      const int X = cell_rect(a, ix, 0).x;
      cv::line(img, {X, a.area.y}, {X, a.area.y + a.area.height - 1}, kWhite, 1);
    }
    for (size_t iy = 1; iy < ny; ++iy) {
      const int Y = cell_rect(a, 0, iy).br().y;
      cv::line(img, {a.area.x, Y}, {a.area.x + a.area.width - 1, Y}, kWhite, 1);
    }
  }
  draw_frame_and_ticks(img, a, st);
  draw_axes_text(img, a, {hershey_text(m.title), hershey_text(m.x_label), hershey_text(m.y_label)}, st);
  const PlotFrame bar = draw_colour_bar(img, L, m, st);
  if (info) *info = chart_image(img, a), info->colour_bar = bar;
  return img;
}

// ---------------------------------------------------------------- band plot

constexpr double kBandAlpha = 0.25;

void validate(const BandPlot& p) {
  check_image_size("BandPlot", p.width, p.height);
  for (const auto& s : p.series)
    if (s.mid.size() != s.x.size() || s.lo.size() != s.x.size() || s.hi.size() != s.x.size())
      throw std::invalid_argument("BandPlot: series '" + s.label + "' has " + std::to_string(s.x.size()) + " x, " +
                                  std::to_string(s.mid.size()) + " mid, " + std::to_string(s.lo.size()) + " lo and " +
                                  std::to_string(s.hi.size()) + " hi values");
}

Axes band_axes(const BandPlot& p, const Style& st) {
  double xlo = kInf, xhi = -kInf, ylo = kInf, yhi = -kInf;
  for (const auto& s : p.series) {
    extend(xlo, xhi, s.x);
    for (const auto* v : {&s.mid, &s.lo, &s.hi}) extend(ylo, yhi, *v, [&](size_t i) { return std::isfinite(s.x[i]); });
  }
  const Range x = resolve_range(NAN, NAN, xlo <= xhi ? xlo : NAN, xlo <= xhi ? xhi : NAN, 0.02);
  const Range y = resolve_range(NAN, NAN, ylo <= yhi ? ylo : NAN, ylo <= yhi ? yhi : NAN);
  return layout_axes({p.width, p.height}, x, y,
                     {hershey_text(p.title), hershey_text(p.x_label), hershey_text(p.y_label)}, st);
}

// Band polygons (area pixels) over the runs where x, lo and hi are all finite.
std::vector<Polyline> band_polygons(const BandSeries& s, const Axes& a) {
  std::vector<Polyline> out;
  const auto ok = [&](size_t i) { return std::isfinite(s.x[i]) && std::isfinite(s.lo[i]) && std::isfinite(s.hi[i]); };
  for (size_t i = 0; i < s.x.size();) {
    if (!ok(i)) { ++i; continue; }
    size_t j = i;
    while (j < s.x.size() && ok(j)) ++j;
    if (j - i >= 2) {
      Polyline pl;
      for (size_t k = i; k < j; ++k) pl.emplace_back(a.ax(s.x[k]), a.ay(s.hi[k]));
      for (size_t k = j; k-- > i;) pl.emplace_back(a.ax(s.x[k]), a.ay(s.lo[k]));
      out.push_back(std::move(pl));
    }
    i = j;
  }
  return out;
}

cv::Mat band_plot_bgr(const BandPlot& p, ChartImage* info) {
  validate(p);
  const Style st = style_for({p.width, p.height});
  const Axes a = band_axes(p, st);
  cv::Mat img(p.height, p.width, CV_8UC3, kWhite);
  draw_grid(img, a);
  cv::Mat roi = img(a.area);
  std::vector<int> requested;
  for (const auto& s : p.series) requested.push_back(s.colour);
  const auto colours = assign_colours(requested);
  // All bands first, then their edges and the lines on top, so no band hides another's line.
  for (size_t i = 0; i < p.series.size(); ++i)
    fill_translucent(roi, band_polygons(p.series[i], a), bgr(palette_colour(colours[i])), kBandAlpha);
  std::vector<LegendEntry> legend;
  for (size_t i = 0; i < p.series.size(); ++i) {
    const BandSeries& s = p.series[i];
    const cv::Scalar c = bgr(palette_colour(colours[i]));
    const Stroke edge{mix(kWhite, c, 0.55), 1, false}, line{c, st.px(2.5), false};
    draw_series(roi, a, s.x, s.lo, edge, st);
    draw_series(roi, a, s.x, s.hi, edge, st);
    draw_series(roi, a, s.x, s.mid, line, st);
    for (size_t k = 0; k < s.bound_x.size() && k < s.bound_y.size(); ++k)
      draw_bound_marker(roi, {a.ax(s.bound_x[k]), a.ay(s.bound_y[k])}, st.px(9), c, st.px(2));
    if (!s.label.empty()) legend.push_back({hershey_text(s.label), line, Swatch::band, kBandAlpha});
    if (!s.bound_label.empty() && !s.bound_x.empty()) legend.push_back({hershey_text(s.bound_label), {c, st.px(2), false}, Swatch::bound});
  }
  draw_frame_and_ticks(img, a, st);
  draw_axes_text(img, a, {hershey_text(p.title), hershey_text(p.x_label), hershey_text(p.y_label)}, st);
  draw_legend(img, a.area, legend, st);
  if (info) *info = chart_image(img, a);
  return img;
}

// ---------------------------------------------------------------- histogram and CDF

void validate(const Histogram& h, const char* what) {
  check_image_size(what, h.width, h.height);
  if (h.bins < 0) throw std::invalid_argument(std::string(what) + ": bins must be >= 0, got " + std::to_string(h.bins));
  if (h.marker_labels.size() > h.markers.size())
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(h.marker_labels.size()) +
                                " marker labels for " + std::to_string(h.markers.size()) + " markers");
}

// Title with the note on values that are not finite, e.g. "Settling time (12 of 500 not settled)".
std::string histogram_title(const Histogram& h) {
  const size_t bad = h.values.size() - finite_count(h.values);
  if (bad == 0) return hershey_text(h.title);
  const std::string note = std::to_string(bad) + " of " + std::to_string(h.values.size()) + " " + h.nan_label;
  return hershey_text(h.title.empty() ? note : h.title + " (" + note + ")");
}

// X range over [lo, hi] and the markers.
Range histogram_x(const Histogram& h, double lo, double hi, double margin) {
  for (double m : h.markers)
    if (std::isfinite(m)) lo = std::min(lo, m), hi = std::max(hi, m);
  return resolve_range(NAN, NAN, lo <= hi ? lo : NAN, lo <= hi ? hi : NAN, margin);
}

// Where the bar of the values that are not finite stands (Histogram::nan_bar): half a bar right of the bins.
struct NanBar {
  double lo, hi;
  int count;
};
NanBar nan_bar_of(const HistogramBins& b) {
  const double end = b.counts.empty() ? 0.0 : b.edge(b.counts.size());
  const double w = b.counts.empty() ? 1.0 : std::max(b.width, (end - b.lo) / 12);
  return {end + 0.5 * w, end + 1.5 * w, b.not_finite};
}

cv::Mat histogram_bgr(const Histogram& h, ChartImage* info) {
  validate(h, "Histogram");
  const Style st = style_for({h.width, h.height});
  const HistogramBins b = calc_histogram_bins(h.values, h.bins);
  const bool nan_bar = h.nan_bar && b.not_finite > 0;
  const NanBar nb = nan_bar_of(b);
  int top = b.counts.empty() ? 0 : *std::max_element(b.counts.begin(), b.counts.end());
  if (nan_bar) top = std::max(top, nb.count);
  const double x_lo = b.counts.empty() ? (nan_bar ? nb.lo : kInf) : b.edge(0);
  const double x_hi = nan_bar ? nb.hi : b.counts.empty() ? -kInf : b.edge(b.counts.size());
  const Range x = histogram_x(h, x_lo, x_hi, 0.03);
  const Range y = top > 0 ? resolve_range(0, NAN, 0, top, 0.06) : Range{0, 1};
  AxesOptions opt;
  opt.y_min_step = 1;
  const AxesText text{histogram_title(h), hershey_text(h.x_label), "count"};
  const Axes a = layout_axes({h.width, h.height}, x, y, text, st, opt);
  cv::Mat img(h.height, h.width, CV_8UC3, kWhite);
  draw_grid(img, a, false, true);
  const cv::Scalar fill = mix(kWhite, bgr(palette_colour(0)), 0.85);
  for (size_t i = 0; i < b.counts.size(); ++i) {
    if (b.counts[i] == 0) continue;
    const int x0 = a.ix(b.edge(i)), x1 = a.ix(b.edge(i + 1));
    const int right = x1 - x0 >= 4 ? x1 - 1 : x1;  // a white pixel between wide bars
    cv::rectangle(img, cv::Point(x0, a.iy(b.counts[i])), cv::Point(right, a.iy(0)), fill, cv::FILLED);
  }
  std::vector<LegendEntry> legend{{"n = " + std::to_string(finite_count(h.values)), {fill, 1, false}, Swatch::box}};
  if (nan_bar) {
    hatch(img, cv::Rect(cv::Point(a.ix(nb.lo), a.iy(nb.count)), cv::Point(a.ix(nb.hi), a.iy(0))), st);
    legend.push_back({hershey_text(h.nan_label + ": " + std::to_string(nb.count)), {kNanFill, 1, false}, Swatch::box});
  }
  for (auto& e : draw_markers(img, a, h, st)) legend.push_back(std::move(e));
  draw_frame_and_ticks(img, a, st);
  draw_axes_text(img, a, text, st);
  draw_legend(img, a.area, legend, st);
  if (info) *info = chart_image(img, a);
  return img;
}

cv::Mat cdf_bgr(const Histogram& h, ChartImage* info) {
  validate(h, "Histogram (CDF)");
  const Style st = style_for({h.width, h.height});
  Ecdf e = calc_ecdf(h.values);
  // nan_bar: fractions of every value, so the curve ends at the finite fraction.
  const size_t finite = finite_count(h.values), bad = h.values.size() - finite;
  const bool nan_mass = h.nan_bar && bad > 0;
  if (nan_mass)
    for (double& p : e.p) p *= double(finite) / double(h.values.size());
  const Range x = e.x.empty() ? histogram_x(h, kInf, -kInf, 0.04) : histogram_x(h, e.x.front(), e.x.back(), 0.04);
  const AxesText text{histogram_title(h), hershey_text(h.x_label), "cumulative fraction"};
  const Axes a = layout_axes({h.width, h.height}, x, {-0.03, 1.03}, text, st);
  cv::Mat img(h.height, h.width, CV_8UC3, kWhite);
  draw_grid(img, a);
  // Steps: flat at 0 from the left edge, up at each value, flat at 1 to the right edge.
  std::vector<double> sx, sy;
  double last = 0;
  if (!e.x.empty()) sx.push_back(x.lo), sy.push_back(0);
  for (size_t i = 0; i < e.x.size(); ++i) {
    sx.push_back(e.x[i]), sy.push_back(last);
    sx.push_back(e.x[i]), sy.push_back(last = e.p[i]);
  }
  if (!e.x.empty()) sx.push_back(x.hi), sy.push_back(last);
  std::vector<LegendEntry> legend;
  if (nan_mass) {
    // The mass that never arrives: shaded from where the curve ends up to 1, right of the largest value.
    const double from = e.x.empty() ? x.lo : e.x.back();
    const double y0 = double(finite) / double(h.values.size());
    const Polyline box{{double(a.ix(from)), double(a.iy(y0))}, {double(a.ix(x.hi)), double(a.iy(y0))},
                       {double(a.ix(x.hi)), double(a.iy(1))}, {double(a.ix(from)), double(a.iy(1))}};
    fill_translucent(img, {box}, kNanHatch, 0.4);
    legend.push_back({hershey_text(h.nan_label + ": " + std::to_string(bad) + " of " + std::to_string(h.values.size())),
                      {kNanHatch, 1, false}, Swatch::box, 0.4});
  }
  const Stroke line{bgr(palette_colour(0)), st.px(2.5), false};
  cv::Mat roi = img(a.area);
  draw_series(roi, a, sx, sy, line, st);
  legend.insert(legend.begin(), {"n = " + std::to_string(e.x.empty() ? 0 : finite), line});
  for (auto& m : draw_markers(img, a, h, st)) legend.push_back(std::move(m));
  draw_frame_and_ticks(img, a, st);
  draw_axes_text(img, a, text, st);
  draw_legend(img, a.area, legend, st);
  if (info) *info = chart_image(img, a);
  return img;
}

// ---------------------------------------------------------------- bar chart

constexpr double kGroupWidth = 0.8;

void validate(const BarChart& b) {
  check_image_size("BarChart", b.width, b.height);
  for (size_t g = 0; g < b.groups.size(); ++g)
    if (b.groups[g].size() != b.names.size())
      throw std::invalid_argument("BarChart: group " + std::to_string(g) + " has " +
                                  std::to_string(b.groups[g].size()) + " values for " + std::to_string(b.names.size()) +
                                  " names");
  if (!b.errors.empty()) {
    if (b.errors.size() != b.groups.size())
      throw std::invalid_argument("BarChart: " + std::to_string(b.errors.size()) + " error groups for " +
                                  std::to_string(b.groups.size()) + " groups");
    for (size_t g = 0; g < b.errors.size(); ++g)
      if (b.errors[g].size() != b.names.size())
        throw std::invalid_argument("BarChart: error group " + std::to_string(g) + " has " +
                                    std::to_string(b.errors[g].size()) + " values for " +
                                    std::to_string(b.names.size()) + " names");
  }
  if (b.group_labels.size() > b.groups.size())
    throw std::invalid_argument("BarChart: " + std::to_string(b.group_labels.size()) + " group labels for " +
                                std::to_string(b.groups.size()) + " groups");
}

double bar_error(const BarChart& b, size_t g, size_t i) {
  if (b.errors.empty()) return 0;
  const double e = std::abs(b.errors[g][i]);
  return std::isfinite(e) ? e : 0;
}

// Y range from zero to the bars and whiskers, with room above (and below, if negative).
Range bar_range(const BarChart& b) {
  double lo = 0, hi = 0;
  for (size_t g = 0; g < b.groups.size(); ++g)
    for (size_t i = 0; i < b.names.size(); ++i) {
      const double v = b.groups[g][i], e = bar_error(b, g, i);
      if (std::isfinite(v)) lo = std::min(lo, v - e), hi = std::max(hi, v + e);
    }
  if (lo == 0 && hi == 0) return {0, 1};
  const double m = 0.06 * (hi - lo);
  return {lo < 0 ? lo - m / 2 : 0, hi > 0 ? hi + m : 0};
}

cv::Mat bar_chart_bgr(const BarChart& b, ChartImage* info) {
  validate(b);
  const Style st = style_for({b.width, b.height});
  AxesOptions opt;
  opt.x_ticks = Ticks{};
  opt.x_min_font = 0.6;  // names rather smaller, or on two rows, than missing
  opt.x_stagger = true;
  for (size_t i = 0; i < b.names.size(); ++i)
    opt.x_ticks->values.push_back(double(i)), opt.x_ticks->labels.push_back(hershey_text(b.names[i]));
  const Range x{-0.5, std::max<double>(double(b.names.size()), 1.0) - 0.5};
  const AxesText text{hershey_text(b.title), "", hershey_text(b.y_label)};
  const Axes a = layout_axes({b.width, b.height}, x, bar_range(b), text, st, opt);
  cv::Mat img(b.height, b.width, CV_8UC3, kWhite);
  draw_grid(img, a, false, true);
  if (a.y.lo < 0) cv::line(img, {a.area.x, a.iy(0)}, {a.area.x + a.area.width - 1, a.iy(0)}, kFrameColour, 1);
  const size_t G = b.groups.size();
  const double bw = kGroupWidth / double(std::max<size_t>(G, 1));
  const int whisker = st.px(1.5);
  const Font small{st.legend.scale * 0.8, st.legend.thickness};
  for (size_t g = 0; g < G; ++g) {
    const cv::Scalar c = bgr(palette_colour(int(g)));
    for (size_t i = 0; i < b.names.size(); ++i) {
      const double centre = double(i) + (double(g) - (double(G) - 1) / 2) * bw, v = b.groups[g][i];
      int x0 = a.ix(centre - bw / 2), x1 = a.ix(centre + bw / 2);
      if (G > 1 && x1 - x0 >= 6) ++x0, --x1;  // a hair of white between neighbouring bars
      if (!std::isfinite(v)) {
        put_text(img, "n/a", {a.ix(centre), a.iy(0) - st.gap}, HAlign::centre, VAlign::bottom,
                 fitted("n/a", small, std::max(1, x1 - x0)), kTickTextColour);
        continue;
      }
      if (v != 0) cv::rectangle(img, cv::Point(x0, a.iy(v)), cv::Point(x1, a.iy(0)), c, cv::FILLED);
      const double e = bar_error(b, g, i);
      if (e > 0) {
        const int cx = a.ix(centre), cap = std::max(2, std::min((x1 - x0) / 4, st.px(8)));
        const int ya = a.iy(v - e), yb = a.iy(v + e);
        cv::line(img, {cx, ya}, {cx, yb}, kTextColour, whisker, cv::LINE_AA);
        cv::line(img, {cx - cap, ya}, {cx + cap, ya}, kTextColour, whisker, cv::LINE_AA);
        cv::line(img, {cx - cap, yb}, {cx + cap, yb}, kTextColour, whisker, cv::LINE_AA);
      }
    }
  }
  std::vector<LegendEntry> legend;
  for (size_t g = 0; g < b.group_labels.size(); ++g)
    if (!b.group_labels[g].empty())
      legend.push_back({hershey_text(b.group_labels[g]), {bgr(palette_colour(int(g))), 1, false}, Swatch::box});
  draw_frame_and_ticks(img, a, st);
  draw_axes_text(img, a, text, st);
  draw_legend(img, a.area, legend, st);
  if (info) *info = chart_image(img, a);
  return img;
}

// Quantile of sorted values, linear between order statistics (R type 7).
double quantile(const std::vector<double>& sorted, double q) {
  const double pos = q * double(sorted.size() - 1);
  const size_t i = size_t(std::floor(pos));
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] + (pos - double(i)) * (sorted[i + 1] - sorted[i]);
}

std::vector<double> sorted_finite(const std::vector<double>& values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  std::sort(v.begin(), v.end());
  return v;
}

}  // namespace

// ---------------------------------------------------------------- public API

Rgb viridis_colour(double t) {
  const auto& table = viridis_table();
  if (!(t > 0)) return table.front();  // also NaN
  if (t >= 1) return table.back();
  const double pos = t * 255;
  const size_t i = size_t(pos);
  const double f = pos - double(i);
  const Rgb a = table[i], b = table[std::min<size_t>(i + 1, 255)];
  const auto lerp = [f](unsigned char p, unsigned char q) { return (unsigned char)std::lround(p + f * (q - p)); };
  return {lerp(a.r, b.r), lerp(a.g, b.g), lerp(a.b, b.b)};
}

int freedman_diaconis_bins(const std::vector<double>& values) {
  const std::vector<double> v = sorted_finite(values);
  if (v.size() < 2) return 1;
  const double n = double(v.size()), range = v.back() - v.front();
  if (range <= 0) return 1;
  const double iqr = quantile(v, 0.75) - quantile(v, 0.25);
  if (!(iqr > 0)) return std::clamp(int(std::ceil(std::log2(n))) + 1, 1, 200);
  const double width = 2 * iqr / std::cbrt(n);
  return int(std::clamp(std::ceil(range / width - 1e-9), 1.0, 200.0));
}

HistogramBins calc_histogram_bins(const std::vector<double>& values, int bins) {
  if (bins < 0) throw std::invalid_argument("calc_histogram_bins: bins must be >= 0, got " + std::to_string(bins));
  HistogramBins out;
  double lo = kInf, hi = -kInf;
  extend(lo, hi, values);
  out.not_finite = int(values.size() - finite_count(values));
  if (lo > hi) return out;
  if (hi == lo) lo -= 0.5, hi += 0.5;
  const int n = bins > 0 ? bins : freedman_diaconis_bins(values);
  out.lo = lo, out.width = (hi - lo) / n;
  out.counts.assign(size_t(n), 0);
  for (double v : values)
    if (std::isfinite(v)) ++out.counts[size_t(std::clamp(int(std::floor((v - lo) / (hi - lo) * n)), 0, n - 1))];
  return out;
}

Ecdf calc_ecdf(const std::vector<double>& values) {
  const std::vector<double> v = sorted_finite(values);
  Ecdf e;
  for (size_t i = 0; i < v.size(); ++i) {
    if (i + 1 < v.size() && v[i + 1] == v[i]) continue;  // last of equal values
    e.x.push_back(v[i]);
    e.p.push_back(i + 1 == v.size() ? 1.0 : double(i + 1) / double(v.size()));
  }
  return e;
}

void render_heat_map(const HeatMap& m, const std::string& png_path) {
  write_png("render_heat_map", heat_map_bgr(m, nullptr), png_path);
}
void render_band_plot(const BandPlot& p, const std::string& png_path) {
  write_png("render_band_plot", band_plot_bgr(p, nullptr), png_path);
}
void render_histogram(const Histogram& h, const std::string& png_path) {
  write_png("render_histogram", histogram_bgr(h, nullptr), png_path);
}
void render_cdf(const Histogram& h, const std::string& png_path) {
  write_png("render_cdf", cdf_bgr(h, nullptr), png_path);
}
void render_bar_chart(const BarChart& b, const std::string& png_path) {
  write_png("render_bar_chart", bar_chart_bgr(b, nullptr), png_path);
}

ChartImage render_heat_map_rgb(const HeatMap& m) {
  ChartImage out;
  heat_map_bgr(m, &out);
  return out;
}
ChartImage render_band_plot_rgb(const BandPlot& p) {
  ChartImage out;
  band_plot_bgr(p, &out);
  return out;
}
ChartImage render_histogram_rgb(const Histogram& h) {
  ChartImage out;
  histogram_bgr(h, &out);
  return out;
}
ChartImage render_cdf_rgb(const Histogram& h) {
  ChartImage out;
  cdf_bgr(h, &out);
  return out;
}
ChartImage render_bar_chart_rgb(const BarChart& b) {
  ChartImage out;
  bar_chart_bgr(b, &out);
  return out;
}

}  // namespace ff
