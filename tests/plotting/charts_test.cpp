// Tests of the chart kinds: heat map colours and colour bar, band fill, histogram bins and
// Freedman–Diaconis, empirical CDF, bar heights and whiskers, PNG output and errors.
#include "plotting/charts.hpp"

#include "tests/plotting/test_support.hpp"

#include <gtest/gtest.h>
// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using ff::test::Image;
using ff::test::is_white;
using ff::test::near;
using ff::test::TempDir;

Image image(const ff::ChartImage& c) { return {c.width, c.height, c.rgb}; }

int px(double v) { return int(std::lround(v)); }

// Mix of white and palette colour c at alpha, as the band fill is drawn.
ff::Rgb tint(ff::Rgb c, double alpha) {
  const auto m = [alpha](int v) { return (unsigned char)std::lround(255 * (1 - alpha) + v * alpha); };
  return {m(c.r), m(c.g), m(c.b)};
}

bool is_grey(ff::Rgb c) { return std::abs(c.r - c.g) <= 2 && std::abs(c.g - c.b) <= 2 && c.r > 120 && c.r < 235; }

// ---------------------------------------------------------------- heat map

ff::HeatMap heat_map_2x3() {
  ff::HeatMap m;
  m.title = "settling time";
  m.x_label = "payload (kg)";
  m.y_label = "stiffness (N.m/rad)";
  m.value_label = "settling time (s)";
  m.x = {100, 200, 300};
  m.y = {1e4, 2e4};
  m.values = {1.0, 2.0, 3.0,   // iy = 0
              4.0, 5.0, 7.0};  // iy = 1
  m.annotate = false;
  return m;
}

TEST(Charts, ViridisRunsFromPurpleToYellow) {
  const ff::Rgb lo = ff::viridis_colour(0), hi = ff::viridis_colour(1);
  EXPECT_TRUE(near(lo, {68, 1, 84}, 3));
  EXPECT_TRUE(near(hi, {253, 231, 37}, 3));
  // Lightness rises monotonically along the map (it is perceptually ordered).
  double last = -1;
  for (int i = 0; i <= 20; ++i) {
    const ff::Rgb c = ff::viridis_colour(i / 20.0);
    const double l = 0.299 * c.r + 0.587 * c.g + 0.114 * c.b;
    EXPECT_GT(l, last) << i;
    last = l;
  }
  EXPECT_TRUE(near(ff::viridis_colour(-3), lo, 0));
  EXPECT_TRUE(near(ff::viridis_colour(7), hi, 0));
}

TEST(Charts, HeatMapCellsFollowTheColourMap) {
  const ff::HeatMap m = heat_map_2x3();
  const ff::ChartImage c = ff::render_heat_map_rgb(m);
  ASSERT_EQ(c.rgb.size(), size_t(m.width) * m.height * 3);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  EXPECT_DOUBLE_EQ(f.x_lo, -0.5);
  EXPECT_DOUBLE_EQ(f.x_hi, 2.5);
  EXPECT_DOUBLE_EQ(f.y_lo, -0.5);
  EXPECT_DOUBLE_EQ(f.y_hi, 1.5);
  const auto cell = [&](int ix, int iy) { return img.at(px(f.x_to_px(ix)), px(f.y_to_px(iy))); };
  // Each cell has the viridis colour of its value scaled to min..max = 1..7.
  for (int iy = 0; iy < 2; ++iy)
    for (int ix = 0; ix < 3; ++ix) {
      const double v = m.values[size_t(iy * 3 + ix)];
      EXPECT_TRUE(near(cell(ix, iy), ff::viridis_colour((v - 1) / 6), 2)) << ix << "," << iy;
    }
  // The lowest value's cell is purple, the highest one's yellowish.
  const ff::Rgb lowest = cell(0, 0), highest = cell(2, 1);
  EXPECT_GT(lowest.b, lowest.g);
  EXPECT_GT(lowest.r, lowest.g);
  EXPECT_LT(lowest.g, 30);
  EXPECT_GT(highest.r, 220);
  EXPECT_GT(highest.g, 200);
  EXPECT_LT(highest.b, 80);
  // Cells are laid out with x to the right and y upwards.
  EXPECT_LT(f.x_to_px(0), f.x_to_px(2));
  EXPECT_GT(f.y_to_px(0), f.y_to_px(1));
}

TEST(Charts, ColourBarSpansMinToMax) {
  const ff::HeatMap m = heat_map_2x3();
  const ff::ChartImage c = ff::render_heat_map_rgb(m);
  const Image img = image(c);
  const ff::PlotFrame& bar = c.colour_bar;
  EXPECT_DOUBLE_EQ(bar.y_lo, 1.0);
  EXPECT_DOUBLE_EQ(bar.y_hi, 7.0);
  EXPECT_GT(bar.left, c.frame.left + c.frame.width);  // right of the cells
  EXPECT_LT(bar.left + bar.width, m.width);
  EXPECT_GT(bar.height, c.frame.height / 2);
  const int x = bar.left + bar.width / 2;
  EXPECT_TRUE(near(img.at(x, bar.top), ff::viridis_colour(1), 3));                   // max at the top
  EXPECT_TRUE(near(img.at(x, bar.top + bar.height - 1), ff::viridis_colour(0), 3));  // min at the bottom
  // Value 4 (half way) sits half way up the bar, in the middle colour of the map.
  EXPECT_TRUE(near(img.at(x, px(bar.y_to_px(4.0))), ff::viridis_colour(0.5), 4));
  // A cell and the bar agree on the colour of a value.
  EXPECT_TRUE(near(img.at(x, px(bar.y_to_px(5.0))),
                   img.at(px(c.frame.x_to_px(1)), px(c.frame.y_to_px(1))), 6));
}

TEST(Charts, NanCellsAreGreyAndLeftOutOfTheRange) {
  ff::HeatMap m = heat_map_2x3();
  m.values[5] = NAN;  // the 7 goes
  m.values[0] = NAN;  // and the 1
  const ff::ChartImage c = ff::render_heat_map_rgb(m);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  // Every pixel of a NaN cell is grey (fill or hatching).
  for (auto [ix, iy] : {std::pair{2, 1}, {0, 0}})
    for (double dx : {-0.3, -0.1, 0.0, 0.2, 0.35})
      for (double dy : {-0.3, 0.0, 0.1, 0.3})
        EXPECT_TRUE(is_grey(img.at(px(f.x_to_px(ix + dx)), px(f.y_to_px(iy + dy))))) << ix << "," << iy;
  // The bar spans the finite values 2..5 and ends above a grey "n/a" swatch.
  EXPECT_DOUBLE_EQ(c.colour_bar.y_lo, 2.0);
  EXPECT_DOUBLE_EQ(c.colour_bar.y_hi, 5.0);
  const int x = c.colour_bar.left + c.colour_bar.width / 2;
  EXPECT_TRUE(is_grey(img.at(x, f.top + f.height - 4)));
  EXPECT_LT(c.colour_bar.top + c.colour_bar.height, f.top + f.height - 10);
  // Finite cells keep their colours on the new scale.
  EXPECT_TRUE(near(img.at(px(f.x_to_px(1)), px(f.y_to_px(1))), ff::viridis_colour(1), 2));
  EXPECT_TRUE(near(img.at(px(f.x_to_px(1)), px(f.y_to_px(0))), ff::viridis_colour(0), 2));
}

// Pixels of a cell's inner half that differ from the cell's corner colour.
int text_pixels(const ff::ChartImage& c, int ix, int iy) {
  const Image img = image(c);
  const ff::Rgb fill = img.at(px(c.frame.x_to_px(ix - 0.4)), px(c.frame.y_to_px(iy - 0.4)));
  int n = 0;
  for (int y = px(c.frame.y_to_px(iy + 0.25)); y <= px(c.frame.y_to_px(iy - 0.25)); ++y)
    for (int x = px(c.frame.x_to_px(ix - 0.25)); x <= px(c.frame.x_to_px(ix + 0.25)); ++x)
      n += !near(img.at(x, y), fill, 3);
  return n;
}

TEST(Charts, LargeCellsAreAnnotated) {
  ff::HeatMap m = heat_map_2x3();
  EXPECT_EQ(text_pixels(ff::render_heat_map_rgb(m), 1, 0), 0);
  m.annotate = true;
  const ff::ChartImage c = ff::render_heat_map_rgb(m);
  EXPECT_GT(text_pixels(c, 1, 0), 20);
  EXPECT_GT(text_pixels(c, 2, 1), 20);  // dark text on yellow
  // Tiny cells (60 x 50) stay plain even when asked.
  ff::HeatMap dense = m;
  dense.x.resize(60), dense.y.resize(50), dense.values.resize(60 * 50);
  std::iota(dense.x.begin(), dense.x.end(), 0.0);
  std::iota(dense.y.begin(), dense.y.end(), 0.0);
  for (size_t i = 0; i < dense.values.size(); ++i) dense.values[i] = double(i % 60) * 1.234;
  const ff::ChartImage d = ff::render_heat_map_rgb(dense);
  EXPECT_EQ(text_pixels(d, 30, 25), 0);
}

TEST(Charts, HeatMapRejectsInconsistentSizes) {
  ff::HeatMap m = heat_map_2x3();
  m.values.pop_back();
  EXPECT_THROW(ff::render_heat_map_rgb(m), std::invalid_argument);
  m = heat_map_2x3();
  m.x.clear();
  EXPECT_THROW(ff::render_heat_map_rgb(m), std::invalid_argument);
}

// Pixels of the top-right quarter of a cell that differ from its centre's colour.
int corner_pixels(const ff::ChartImage& c, int ix, int iy) {
  const Image img = image(c);
  const ff::Rgb fill = img.at(px(c.frame.x_to_px(ix)), px(c.frame.y_to_px(iy)));
  int n = 0;
  for (int y = px(c.frame.y_to_px(iy + 0.45)); y <= px(c.frame.y_to_px(iy + 0.05)); ++y)
    for (int x = px(c.frame.x_to_px(ix + 0.05)); x <= px(c.frame.x_to_px(ix + 0.45)); ++x) n += !near(img.at(x, y), fill, 3);
  return n;
}

// (#32.11) A cell whose value is a lower bound (runs not settled, counted at their horizon) carries the
// bound marker in its corner, visible without the annotation; annotated, it reads "> v" (wider text).
TEST(Charts, HeatMapBoundCellsAreMarkedAsLowerBounds) {
  ff::HeatMap m = heat_map_2x3();
  m.bounds = {0, 1, 0, 0, 0, 1};
  const ff::ChartImage c = ff::render_heat_map_rgb(m);
  EXPECT_GT(corner_pixels(c, 1, 0), 20);
  EXPECT_GT(corner_pixels(c, 2, 1), 20);  // dark on yellow
  for (auto [ix, iy] : {std::pair{0, 0}, {2, 0}, {0, 1}, {1, 1}}) EXPECT_EQ(corner_pixels(c, ix, iy), 0) << ix << "," << iy;
  m.annotate = true;
  ff::HeatMap plain = m;
  plain.bounds.clear();
  EXPECT_GT(text_pixels(ff::render_heat_map_rgb(m), 1, 0), text_pixels(ff::render_heat_map_rgb(plain), 1, 0) + 10);
  m.bounds.pop_back();
  EXPECT_THROW(ff::render_heat_map_rgb(m), std::invalid_argument);
}

// ---------------------------------------------------------------- band plot

TEST(Charts, BandIsFilledBetweenLoAndHi) {
  ff::BandPlot p;
  p.title = "band";
  p.x_label = "time (s)";
  p.y_label = "tip (mm)";
  ff::BandSeries s;
  s.label = "p50, p5..p95";
  for (int i = 0; i <= 100; ++i) {
    const double x = i * 0.1;
    s.x.push_back(x), s.mid.push_back(0.5), s.lo.push_back(-1 - 0.1 * x), s.hi.push_back(2 + 0.1 * x);
  }
  p.series = {s};
  const ff::ChartImage c = ff::render_band_plot_rgb(p);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  const ff::Rgb line = ff::palette_colour(0), fill = tint(line, 0.25);
  // At x = 3.3 (off the grid lines): band colour from hi to lo, except around the mid line.
  const int col = px(f.x_to_px(3.3));
  const int top = px(f.y_to_px(2.33)), bottom = px(f.y_to_px(-1.33)), mid = px(f.y_to_px(0.5));
  int inside = 0, banded = 0;
  for (int y = top + 3; y <= bottom - 3; ++y) {
    if (std::abs(y - mid) <= 5) continue;
    ++inside;
    banded += near(img.at(col, y), fill, 4);
  }
  ASSERT_GT(inside, 100);
  EXPECT_GE(banded, inside * 9 / 10) << banded << " of " << inside;
  EXPECT_TRUE(near(img.at(col, mid), line, 12));  // the solid line on top
  // Outside the band: no fill.
  for (int y : {top - 6, top - 12, bottom + 6, bottom + 12}) EXPECT_FALSE(near(img.at(col, y), fill, 4)) << y;
  // The x range covers the data, the y range the band.
  EXPECT_LE(f.x_lo, 0);
  EXPECT_GE(f.x_hi, 10);
  EXPECT_LE(f.y_lo, -2);
  EXPECT_GE(f.y_hi, 3);
}

TEST(Charts, BandNanLeavesAGap) {
  ff::BandPlot p;
  ff::BandSeries s;
  for (int i = 0; i <= 10; ++i) s.x.push_back(i), s.mid.push_back(0), s.lo.push_back(-1), s.hi.push_back(1);
  s.lo[5] = NAN;
  p.series = {s};
  const ff::ChartImage c = ff::render_band_plot_rgb(p);
  const Image img = image(c);
  const ff::Rgb fill = tint(ff::palette_colour(0), 0.25);
  const int y = px(c.frame.y_to_px(0.55));
  EXPECT_TRUE(near(img.at(px(c.frame.x_to_px(2.3)), y), fill, 4));
  EXPECT_FALSE(near(img.at(px(c.frame.x_to_px(5)), y), fill, 4));
}

// (#32.11) A percentile above the horizon, drawn at it, is marked as a lower bound where it stands.
TEST(Charts, BandPointsThatAreLowerBoundsCarryTheBoundMarker) {
  ff::BandPlot p;
  ff::BandSeries s;
  for (int i = 0; i <= 10; ++i) s.x.push_back(i), s.mid.push_back(1), s.lo.push_back(0), s.hi.push_back(i < 7 ? 2 : 3);
  p.series = {s};
  const Image plain = image(ff::render_band_plot_rgb(p));
  p.series[0].bound_x = {8.0};
  p.series[0].bound_y = {3.0};
  const ff::ChartImage c = ff::render_band_plot_rgb(p);
  const Image marked = image(c);
  int changed = 0;
  for (int y = px(c.frame.y_to_px(3.2)); y <= px(c.frame.y_to_px(2.8)); ++y)
    for (int x = px(c.frame.x_to_px(7.8)); x <= px(c.frame.x_to_px(8.2)); ++x) changed += !near(marked.at(x, y), plain.at(x, y), 3);
  EXPECT_GT(changed, 20);
  // Nowhere near the other points.
  for (int y = px(c.frame.y_to_px(2.2)); y <= px(c.frame.y_to_px(1.8)); ++y)
    EXPECT_TRUE(near(marked.at(px(c.frame.x_to_px(3.5)), y), plain.at(px(c.frame.x_to_px(3.5)), y), 3)) << y;
}

TEST(Charts, BandRejectsMismatchedLengths) {
  ff::BandPlot p;
  p.series = {{"s", {0, 1, 2}, {0, 1, 2}, {0, 1}, {0, 1, 2}, -1}};
  EXPECT_THROW(ff::render_band_plot_rgb(p), std::invalid_argument);
}

// ---------------------------------------------------------------- histogram and CDF

std::vector<double> zero_to(int n) {
  std::vector<double> v(size_t(n) + 1);
  std::iota(v.begin(), v.end(), 0.0);
  return v;
}

TEST(Charts, HistogramBinsCountEqualWidths) {
  const auto b = ff::calc_histogram_bins(zero_to(99), 10);
  ASSERT_EQ(b.counts.size(), 10u);
  for (int c : b.counts) EXPECT_EQ(c, 10);
  EXPECT_DOUBLE_EQ(b.lo, 0);
  EXPECT_DOUBLE_EQ(b.width, 9.9);
  EXPECT_DOUBLE_EQ(b.edge(10), 99);
  EXPECT_EQ(b.not_finite, 0);
  // NaN and inf are counted apart; the max lands in the last bin.
  auto v = zero_to(99);
  v.insert(v.end(), {NAN, INFINITY, NAN});
  const auto c = ff::calc_histogram_bins(v, 10);
  EXPECT_EQ(c.counts, b.counts);
  EXPECT_EQ(c.not_finite, 3);
  // Uneven data: 1, 1, 2, 9 in 4 bins of width 2 from 1.
  const auto d = ff::calc_histogram_bins({2, 1, 9, 1}, 4);
  EXPECT_EQ(d.counts, (std::vector<int>{3, 0, 0, 1}));
  EXPECT_DOUBLE_EQ(d.width, 2);
  // One distinct value: one bin around it. No finite values: no bins.
  const auto e = ff::calc_histogram_bins({3, 3, 3}, 0);
  ASSERT_EQ(e.counts.size(), 1u);
  EXPECT_EQ(e.counts[0], 3);
  EXPECT_DOUBLE_EQ(e.lo, 2.5);
  EXPECT_TRUE(ff::calc_histogram_bins({NAN, NAN}, 5).counts.empty());
  EXPECT_EQ(ff::calc_histogram_bins({NAN, NAN}, 5).not_finite, 2);
  EXPECT_THROW(ff::calc_histogram_bins({1, 2}, -1), std::invalid_argument);
}

TEST(Charts, FreedmanDiaconisBinCount) {
  // 0..99: IQR = 74.25 - 24.75 = 49.5, width 2 * 49.5 / 100^(1/3) = 21.33, range 99 -> 5 bins (as numpy 'fd').
  EXPECT_EQ(ff::freedman_diaconis_bins(zero_to(99)), 5);
  // 0..999: IQR 499.5, width 2 * 499.5 / 10 = 99.9 (n^(1/3) = 10.0), range 999 -> 10 bins.
  EXPECT_EQ(ff::freedman_diaconis_bins(zero_to(999)), 10);
  // NaNs do not count.
  auto v = zero_to(99);
  v.push_back(NAN);
  EXPECT_EQ(ff::freedman_diaconis_bins(v), 5);
  // Zero IQR: Sturges, ceil(log2 9) + 1 = 5; fewer than two values or no spread: 1.
  EXPECT_EQ(ff::freedman_diaconis_bins({0, 0, 0, 0, 0, 0, 0, 0, 1}), 5);
  EXPECT_EQ(ff::freedman_diaconis_bins({4.2}), 1);
  EXPECT_EQ(ff::freedman_diaconis_bins({2, 2, 2}), 1);
  // bins = 0 in calc_histogram_bins takes it.
  EXPECT_EQ(ff::calc_histogram_bins(zero_to(99)).counts.size(), 5u);
}

// Topmost row of column x inside the frame with colour c (tolerance tol), or -1.
int top_of(const Image& img, const ff::PlotFrame& f, int x, ff::Rgb c, int tol = 6) {
  for (int y = f.top; y < f.top + f.height; ++y)
    if (near(img.at(x, y), c, tol)) return y;
  return -1;
}

TEST(Charts, HistogramBarsReachTheirCounts) {
  ff::Histogram h;
  h.title = "settling";
  h.x_label = "time (s)";
  h.values = {1, 1, 1, 1, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, NAN, NAN};
  h.bins = 3;  // counts 4, 2, 8 over [1, 1.67), [1.67, 2.33), [2.33, 3]
  h.nan_label = "not settled";
  const ff::ChartImage c = ff::render_histogram_rgb(h);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  EXPECT_DOUBLE_EQ(f.y_lo, 0);
  EXPECT_GE(f.y_hi, 8);
  const ff::Rgb fill = tint(ff::palette_colour(0), 0.85);
  const std::vector<int> counts{4, 2, 8};
  for (int i = 0; i < 3; ++i) {
    const double centre = 1 + (i + 0.5) * 2.0 / 3;
    const int top = top_of(img, f, px(f.x_to_px(centre)), fill);
    EXPECT_NEAR(top, f.y_to_px(counts[size_t(i)]), 2) << "bin " << i;
  }
  // The NaN note changes the title (and only the title band) against the same data without NaN.
  ff::Histogram clean = h;
  clean.values.resize(14);
  const Image without = image(ff::render_histogram_rgb(clean));
  int differ_above = 0, differ_below = 0;
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x)
      (y < f.top - 2 ? differ_above : differ_below) += !near(img.at(x, y), without.at(x, y), 0);
  EXPECT_GT(differ_above, 100);
  EXPECT_LT(differ_below, 200);  // the "n = ..." legend text only
}

TEST(Charts, CdfReachesOneAtTheMax) {
  const ff::Ecdf e = ff::calc_ecdf({3, NAN, 1, 2, 2, 5});
  EXPECT_EQ(e.x, (std::vector<double>{1, 2, 3, 5}));
  ASSERT_EQ(e.p.size(), 4u);
  EXPECT_DOUBLE_EQ(e.p[0], 0.2);
  EXPECT_DOUBLE_EQ(e.p[1], 0.6);
  EXPECT_DOUBLE_EQ(e.p[2], 0.8);
  EXPECT_DOUBLE_EQ(e.p.back(), 1.0);
  const ff::Ecdf f = ff::calc_ecdf(zero_to(99));
  EXPECT_DOUBLE_EQ(f.x.back(), 99);
  EXPECT_DOUBLE_EQ(f.p.back(), 1.0);
  for (size_t i = 1; i < f.p.size(); ++i) EXPECT_GT(f.p[i], f.p[i - 1]);
  EXPECT_TRUE(ff::calc_ecdf({NAN}).x.empty());
}

// Whether column x has a pixel of colour c within 3 rows of row y.
bool colour_near(const Image& img, int x, int y, ff::Rgb c, int tol = 30) {
  for (int dy = -3; dy <= 3; ++dy)
    if (near(img.at(x, y + dy), c, tol)) return true;
  return false;
}

TEST(Charts, CdfPlotStepsFromZeroToOne) {
  ff::Histogram h;
  h.x_label = "time (s)";
  h.values = zero_to(99);
  h.markers = {50};
  h.marker_labels = {"median"};
  const ff::ChartImage c = ff::render_cdf_rgb(h);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  EXPECT_LT(f.y_lo, 0);
  EXPECT_GT(f.y_hi, 1);
  EXPECT_LT(f.y_hi, 1.1);
  const ff::Rgb line = ff::palette_colour(0);
  EXPECT_TRUE(colour_near(img, px(f.x_to_px(-2)), px(f.y_to_px(0)), line));     // 0 left of the min
  EXPECT_TRUE(colour_near(img, px(f.x_to_px(101)), px(f.y_to_px(1)), line));    // 1 right of the max
  EXPECT_TRUE(colour_near(img, px(f.x_to_px(24.5)), px(f.y_to_px(0.25)), line));
  // The marker is a dashed vertical line in palette colour 1.
  const int mx = px(f.x_to_px(50));
  int on = 0;
  for (int y = f.top; y < f.top + f.height; ++y) on += near(img.at(mx, y), ff::palette_colour(1), 40);
  EXPECT_GT(on, f.height / 3);
  EXPECT_LT(on, f.height * 9 / 10);
}

TEST(Charts, NotSettledValuesStandAsABarOfTheirOwn) {
  // Counts 4, 2, 8 over [1, 3] and 5 not settled: a grey bar of height 5 half a bin right of the bins.
  ff::Histogram h;
  h.x_label = "time (s)";
  h.values = {1, 1, 1, 1, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, NAN, NAN, NAN, NAN, NAN};
  h.bins = 3;
  h.nan_label = "not settled";
  h.nan_bar = true;
  const ff::ChartImage c = ff::render_histogram_rgb(h);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  EXPECT_GE(f.x_hi, 4.0);  // the bar spans 3 1/3 .. 4
  const int x = px(f.x_to_px(3 + 2.0 / 3));
  EXPECT_TRUE(is_grey(img.at(x, px(f.y_to_px(2.5)))));
  EXPECT_TRUE(is_grey(img.at(x, px(f.y_to_px(4.8)))));
  EXPECT_FALSE(is_grey(img.at(x, px(f.y_to_px(5.3)))));
  EXPECT_TRUE(is_white(img.at(px(f.x_to_px(3 + 1.0 / 6)), px(f.y_to_px(1.5)))));  // the gap before it
  // Without nan_bar the same values keep to the bins (and only the title counts the NaNs).
  h.nan_bar = false;
  EXPECT_LT(ff::render_histogram_rgb(h).frame.x_hi, 3.2);
}

TEST(Charts, CdfWithNotSettledStopsAtTheSettledFraction) {
  // 100 values 0..99 and 25 not settled: fractions of all 125, so the curve ends at 0.8, the rest shaded grey.
  ff::Histogram h;
  h.x_label = "time (s)";
  h.values = zero_to(99);
  h.values.resize(125, NAN);
  h.nan_label = "not settled";
  h.nan_bar = true;
  const ff::ChartImage c = ff::render_cdf_rgb(h);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  const ff::Rgb line = ff::palette_colour(0);
  EXPECT_TRUE(colour_near(img, px(f.x_to_px(49.5)), px(f.y_to_px(0.4)), line));  // 50 of 125 at or below 49
  EXPECT_TRUE(colour_near(img, px(f.x_to_px(101)), px(f.y_to_px(0.8)), line));   // flat at 0.8 right of the max
  EXPECT_FALSE(colour_near(img, px(f.x_to_px(101)), px(f.y_to_px(1)), line));
  EXPECT_TRUE(is_grey(img.at(px(f.x_to_px(101)), px(f.y_to_px(0.9)))));  // the mass that never settles
  EXPECT_FALSE(is_grey(img.at(px(f.x_to_px(47.3)), px(f.y_to_px(0.93)))));  // off the grid lines
}

TEST(Charts, HistogramRejectsBadInput) {
  ff::Histogram h;
  h.values = {1, 2};
  h.bins = -2;
  EXPECT_THROW(ff::render_histogram_rgb(h), std::invalid_argument);
  h.bins = 0;
  h.marker_labels = {"a"};
  EXPECT_THROW(ff::render_cdf_rgb(h), std::invalid_argument);
}

// ---------------------------------------------------------------- bar chart

TEST(Charts, BarHeightsAreProportionalToValues) {
  ff::BarChart b;
  b.title = "Sobol' indices";
  b.y_label = "index (1)";
  b.names = {"payload", "stiffness", "damping", "inertia"};
  b.groups = {{0.1, 0.2, 0.4, 0.8}, {0.15, 0.3, 0.05, 0.6}};  // no labels: no legend boxes in the columns
  const ff::ChartImage c = ff::render_bar_chart_rgb(b);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  EXPECT_DOUBLE_EQ(f.y_lo, 0);
  const double px_per_unit = (f.height - 1) / (f.y_hi - f.y_lo);
  const int base = px(f.y_to_px(0));
  for (size_t g = 0; g < 2; ++g)
    for (size_t i = 0; i < 4; ++i) {
      const double centre = double(i) + (double(g) - 0.5) * 0.4;
      const int top = top_of(img, f, px(f.x_to_px(centre)), ff::palette_colour(int(g)), 2);
      ASSERT_GE(top, 0) << g << "," << i;
      EXPECT_NEAR(base - top, b.groups[g][i] * px_per_unit, 2) << g << "," << i;
    }
  // Nothing of a bar's colour between categories.
  EXPECT_EQ(top_of(img, f, px(f.x_to_px(0.5)), ff::palette_colour(0), 2), -1);
}

TEST(Charts, ErrorWhiskersSpanTheHalfWidths) {
  ff::BarChart b;
  b.names = {"a", "b"};
  b.groups = {{0.5, 0.25}};
  b.errors = {{0.1, 0.05}};
  const ff::ChartImage c = ff::render_bar_chart_rgb(b);
  const Image img = image(c);
  const ff::PlotFrame& f = c.frame;
  EXPECT_GE(f.y_hi, 0.6);  // the range includes the whisker tops
  for (size_t i = 0; i < 2; ++i) {
    const int x = px(f.x_to_px(double(i)));
    int top = -1;
    for (int y = f.top; y < f.top + f.height && top < 0; ++y) {
      const ff::Rgb p = img.at(x, y);
      if (p.r < 100 && p.g < 100 && p.b < 100) top = y;  // dark whisker
    }
    EXPECT_NEAR(top, f.y_to_px(b.groups[0][i] + b.errors[0][i]), 2) << i;
  }
}

TEST(Charts, BarChartRejectsMismatchedShapes) {
  ff::BarChart b;
  b.names = {"a", "b"};
  b.groups = {{1, 2, 3}};
  EXPECT_THROW(ff::render_bar_chart_rgb(b), std::invalid_argument);
  b.groups = {{1, 2}};
  b.errors = {{0.1}};
  EXPECT_THROW(ff::render_bar_chart_rgb(b), std::invalid_argument);
}

// ---------------------------------------------------------------- files

struct Writer {
  std::string name;
  std::function<void(const std::string&)> render;
  int width, height;
};

std::vector<Writer> writers() {
  ff::HeatMap m = heat_map_2x3();
  ff::BandPlot p;
  p.series = {{"s", {0, 1, 2}, {0, 1, 0}, {-1, 0, -1}, {1, 2, 1}, -1}};
  ff::Histogram h;
  h.values = zero_to(20);
  ff::BarChart b;
  b.names = {"a"};
  b.groups = {{1.0}};
  return {{"heat map", [m](const std::string& s) { ff::render_heat_map(m, s); }, m.width, m.height},
          {"band plot", [p](const std::string& s) { ff::render_band_plot(p, s); }, p.width, p.height},
          {"histogram", [h](const std::string& s) { ff::render_histogram(h, s); }, h.width, h.height},
          {"cdf", [h](const std::string& s) { ff::render_cdf(h, s); }, h.width, h.height},
          {"bar chart", [b](const std::string& s) { ff::render_bar_chart(b, s); }, b.width, b.height}};
}

TEST(Charts, WritePngsAtomically) {
  TempDir dir;
  for (const Writer& w : writers()) {
    const std::string png = (dir.path / "chart.png").string();
    w.render(png);
    const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty()) << w.name;
    EXPECT_EQ(img.cols, w.width) << w.name;
    EXPECT_EQ(img.rows, w.height) << w.name;
    EXPECT_FALSE(std::filesystem::exists(png + ".tmp")) << w.name;
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 1) << w.name;
  }
}

TEST(Charts, UnwritablePathsThrowNamingThePath) {
  TempDir dir;
  const std::string png = (dir.path / "no_such_dir" / "chart.png").string();
  for (const Writer& w : writers()) {
    try {
      w.render(png);
      ADD_FAILURE() << w.name << ": no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << w.name << ": " << e.what();
    }
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 0);
}

}  // namespace
