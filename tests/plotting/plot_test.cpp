// Tests of the plotting library: tick maths, label text, colours, data mapping, NaN gaps, PNG output.
#include "plotting/plot.hpp"

#include "tests/plotting/test_support.hpp"

#include <gtest/gtest.h>
// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using ff::test::Image;
using ff::test::is_white;
using ff::test::near;
using ff::test::TempDir;

Image render(const ff::LinePlot& p) { return {p.width, p.height, ff::render_line_plot_rgb(p)}; }

// Pixels of colour c inside the frame's plot area.
int count_in_frame(const Image& img, const ff::PlotFrame& f, ff::Rgb c) {
  int n = 0;
  for (int y = f.top; y < f.top + f.height; ++y)
    for (int x = f.left; x < f.left + f.width; ++x) n += near(img.at(x, y), c);
  return n;
}

// Whether column x has a pixel of colour c within 4 rows of row y.
bool colour_near(const Image& img, int x, int y, ff::Rgb c) {
  for (int dy = -4; dy <= 4; ++dy)
    if (near(img.at(x, y + dy), c)) return true;
  return false;
}

void expect_ticks(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12) << "tick " << i;
}

ff::Series line(std::vector<double> x, std::vector<double> y, int colour = -1) {
  ff::Series s;
  s.x = std::move(x), s.y = std::move(y), s.colour = colour;
  return s;
}

TEST(Plot, NiceTicksFollowOneTwoFiveSteps) {
  expect_ticks(ff::calc_nice_ticks(0, 1), {0, 0.2, 0.4, 0.6, 0.8, 1.0});
  expect_ticks(ff::calc_nice_ticks(-0.013, 0.512), {0, 0.1, 0.2, 0.3, 0.4, 0.5});
  expect_ticks(ff::calc_nice_ticks(0, 20, 5), {0, 5, 10, 15, 20});
  EXPECT_DOUBLE_EQ(ff::nice_tick_step(0, 20, 5), 5);
  expect_ticks(ff::calc_nice_ticks(-3, 7, 6), {-2, 0, 2, 4, 6});
  expect_ticks(ff::calc_nice_ticks(1, 0), {0, 0.2, 0.4, 0.6, 0.8, 1.0});  // reversed range
  // Every step is 1, 2 or 5 times a power of ten, and ticks lie inside the range.
  for (double hi : {0.003, 0.7, 1.3, 9.0, 42.0, 999.0, 3.3e6}) {
    const double step = ff::nice_tick_step(0, hi);
    const double m = step / std::pow(10.0, std::floor(std::log10(step) + 1e-9));
    EXPECT_TRUE(std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9) << hi;
    const auto t = ff::calc_nice_ticks(0, hi);
    EXPECT_GE(t.size(), 3u) << hi;
    EXPECT_LE(t.size(), 11u) << hi;
    EXPECT_GE(t.front(), -1e-12);
    EXPECT_LE(t.back(), hi * (1 + 1e-9));
  }
  // Degenerate ranges still give at least two ticks around the value.
  for (double v : {0.0, 1.0, -250.0, 1e-7}) {
    const auto t = ff::calc_nice_ticks(v, v);
    ASSERT_GE(t.size(), 2u) << v;
    EXPECT_LE(t.front(), v);
    EXPECT_GE(t.back(), v);
  }
  EXPECT_GE(ff::calc_nice_ticks(0.95, 1.05, 2).size(), 2u);
  EXPECT_THROW(ff::calc_nice_ticks(0, NAN), std::invalid_argument);
}

TEST(Plot, TickLabelsAreShortAndDistinct) {
  EXPECT_EQ(ff::format_tick(0, 0.2), "0");
  EXPECT_EQ(ff::format_tick(0.5, 0.1), "0.5");
  EXPECT_EQ(ff::format_tick(-0.2, 0.2), "-0.2");
  EXPECT_EQ(ff::format_tick(1.0, 0.2), "1.0");  // same decimals as the rest of the axis
  EXPECT_EQ(ff::format_tick(15, 5), "15");
  EXPECT_EQ(ff::format_tick(0.6000000000000001, 0.2), "0.6");
  EXPECT_EQ(ff::format_tick(0.025, 0.005), "0.025");
  EXPECT_EQ(ff::format_tick(1e5, 1e5), "1e+05");
  EXPECT_EQ(ff::format_tick(3e-5, 1e-5), "3e-05");
  EXPECT_EQ(ff::format_tick(1e-17, 0.1), "0");  // rounding residue is not "-0.0" or "1e-17"
  EXPECT_EQ(ff::format_tick(-1e-17, 0.1), "0");
  // Along real axes: labels distinct, short, and parse back to the tick value.
  const std::vector<std::pair<double, double>> ranges{
      {0, 1}, {-0.013, 0.512}, {0, 20}, {-3e-6, 7e-6}, {0, 2.5e6}, {1000, 1000.5}, {-1, 1}, {0, 0.0004}};
  for (auto [lo, hi] : ranges) {
    const auto t = ff::calc_nice_ticks(lo, hi);
    const double step = ff::nice_tick_step(lo, hi);
    std::set<std::string> seen;
    for (double v : t) {
      const std::string s = ff::format_tick(v, step);
      EXPECT_LE(s.size(), 8u) << s;
      EXPECT_TRUE(seen.insert(s).second) << "duplicate " << s << " in " << lo << ".." << hi;
      EXPECT_NEAR(std::stod(s), v, step * 1e-6) << s;
    }
  }
}

TEST(Plot, PaletteIsDistinctAndWraps) {
  const int n = ff::palette_size();
  ASSERT_GE(n, 6);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) EXPECT_FALSE(near(ff::palette_colour(i), ff::palette_colour(j), 30)) << i << j;
  EXPECT_TRUE(near(ff::palette_colour(n), ff::palette_colour(0), 0));
  EXPECT_TRUE(near(ff::palette_colour(-1), ff::palette_colour(n - 1), 0));
  const ff::Rgb first = ff::palette_colour(0);  // Okabe-Ito blue
  EXPECT_EQ(first.r, 0);
  EXPECT_EQ(first.g, 114);
  EXPECT_EQ(first.b, 178);
}

TEST(Plot, SeriesAreDrawnInTheirPaletteColour) {
  ff::LinePlot p;
  p.title = "two lines";
  p.x_label = "time (s)";
  p.y_label = "value (1)";
  p.series = {line({0, 10}, {0.2, 0.3}), line({0, 10}, {0.8, 0.7}), line({0, 10}, {0.5, 0.5}, 4)};
  p.series[0].label = "low";
  p.series[1].label = "high";
  const Image img = render(p);
  ASSERT_EQ(img.rgb.size(), size_t(p.width) * p.height * 3);
  const ff::PlotFrame f = ff::line_plot_frame(p);
  // Automatic colours take palette 0 and 1, the explicit one palette 4; each spans the plot.
  for (int c : {0, 1, 4}) EXPECT_GT(count_in_frame(img, f, ff::palette_colour(c)), f.width) << "palette " << c;
  EXPECT_LT(count_in_frame(img, f, ff::palette_colour(2)), 20);
  // The lines run where the data says: palette 0 at y=0.25 mid-plot, palette 1 at y=0.75.
  const double xm = f.x_to_px(5);
  EXPECT_TRUE(colour_near(img, int(xm), int(std::lround(f.y_to_px(0.25))), ff::palette_colour(0)));
  EXPECT_TRUE(colour_near(img, int(xm), int(std::lround(f.y_to_px(0.75))), ff::palette_colour(1)));
  // White background at the corners.
  for (auto [x, y] : {std::pair{0, 0}, {p.width - 1, 0}, {0, p.height - 1}, {p.width - 1, p.height - 1}})
    EXPECT_TRUE(is_white(img.at(x, y))) << x << "," << y;
}

TEST(Plot, DataMapsInsideTheFrame) {
  ff::LinePlot p;
  p.x_label = "x (m)";
  p.y_label = "y (m)";
  p.x_min = 0, p.x_max = 10, p.y_min = -1, p.y_max = 1;
  p.series = {line({0, 10}, {1, -1})};  // from the top-left corner to the bottom-right one
  const ff::PlotFrame f = ff::line_plot_frame(p);
  EXPECT_EQ(f.x_lo, 0);
  EXPECT_EQ(f.x_hi, 10);
  EXPECT_EQ(f.y_lo, -1);
  EXPECT_EQ(f.y_hi, 1);
  EXPECT_GT(f.left, 40);  // room for tick labels and the y label
  EXPECT_GT(f.top, 5);
  EXPECT_LT(f.left + f.width, p.width);
  EXPECT_LT(f.top + f.height, p.height - 40);
  const Image img = render(p);
  const ff::Rgb c = ff::palette_colour(0);
  // The line's pixels nearest each corner of the plot area are within 2 px of it.
  const auto nearest = [&](int cx, int cy) {
    double best = 1e9;
    for (int y = f.top; y < f.top + f.height; ++y)
      for (int x = f.left; x < f.left + f.width; ++x)
        if (near(img.at(x, y), c, 40)) best = std::min(best, std::hypot(x - cx, y - cy));
    return best;
  };
  EXPECT_LE(nearest(f.left, f.top), 2.0);
  EXPECT_LE(nearest(f.left + f.width - 1, f.top + f.height - 1), 2.0);
  // Nothing of the series outside the area; the frame is just outside it.
  for (int x = 0; x < p.width; ++x) EXPECT_FALSE(near(img.at(x, f.top - 3), c, 40)) << x;
  const ff::Rgb frame = img.at(f.left + f.width / 3, f.top - 1);
  EXPECT_LT(frame.r, 128);
}

TEST(Plot, NanBreaksTheLine) {
  ff::LinePlot p;
  p.x_min = 0, p.x_max = 10, p.y_min = 0, p.y_max = 1;
  std::vector<double> x, y;
  for (int i = 0; i <= 10; ++i) x.push_back(i), y.push_back(0.5);
  p.series = {line(x, y)};
  const ff::PlotFrame f = ff::line_plot_frame(p);
  const int row = int(std::lround(f.y_to_px(0.5)));
  const ff::Rgb c = ff::palette_colour(0);
  const auto col = [&](double xv) { return int(std::lround(f.x_to_px(xv))); };
  EXPECT_TRUE(colour_near(render(p), col(5), row, c));  // unbroken line crosses x = 5
  p.series[0].y[5] = NAN;                                // now the line stops at x = 4 and restarts at 6
  const Image img = render(p);
  EXPECT_TRUE(colour_near(img, col(2), row, c));
  EXPECT_TRUE(colour_near(img, col(8), row, c));
  EXPECT_FALSE(colour_near(img, col(4.5), row, c));
  EXPECT_FALSE(colour_near(img, col(5), row, c));
  EXPECT_FALSE(colour_near(img, col(5.5), row, c));
}

TEST(Plot, MarkersOnlySeriesDrawCrossesAndNoLine) {
  ff::LinePlot p;
  p.x_min = 0, p.x_max = 10, p.y_min = 0, p.y_max = 1;
  p.series = {line({2, 8}, {0.5, 0.5})};
  p.series[0].line = false;
  p.series[0].marker = ff::Series::Marker::kCross;
  const ff::PlotFrame f = ff::line_plot_frame(p);
  const Image img = render(p);
  const ff::Rgb c = ff::palette_colour(0);
  const int row = int(std::lround(f.y_to_px(0.5)));
  const auto col = [&](double xv) { return int(std::lround(f.x_to_px(xv))); };
  EXPECT_TRUE(colour_near(img, col(2), row, c));   // the crosses' centres
  EXPECT_TRUE(colour_near(img, col(8), row, c));
  EXPECT_FALSE(colour_near(img, col(5), row, c));  // nothing joins them
  // A cross has arms on both diagonals: pixels 4 px up-left and up-right of its centre, none 12 px above.
  EXPECT_TRUE(near(img.at(col(2) - 4, row - 4), c, 60));
  EXPECT_TRUE(near(img.at(col(2) + 4, row - 4), c, 60));
  EXPECT_FALSE(near(img.at(col(2), row - 12), c, 60));
}

TEST(Plot, DashedLinesHaveGaps) {
  ff::LinePlot p;
  p.x_min = 0, p.x_max = 10, p.y_min = 0, p.y_max = 1;
  p.series = {line({0, 10}, {0.5, 0.5})};
  p.series[0].dashed = true;
  const ff::PlotFrame f = ff::line_plot_frame(p);
  const Image img = render(p);
  const int row = int(std::lround(f.y_to_px(0.5)));
  int on = 0;
  for (int x = f.left; x < f.left + f.width; ++x) on += near(img.at(x, row), ff::palette_colour(0), 40);
  EXPECT_GT(on, f.width / 3);
  EXPECT_LT(on, f.width * 9 / 10);
}

TEST(Plot, TextStaysInsideTheImage) {
  ff::LinePlot p;
  p.title = "a rather long title that still has to fit on a small plot without being clipped";
  p.x_label = "time (s)";
  p.y_label = "bending moment (N\u00b7m)";
  p.width = 480, p.height = 320;
  p.series = {line({0, 1e6}, {-12345.6, 98765.4})};
  p.series[0].label = "moment";
  p.hlines = {{0.0, "zero \u00b1 nothing"}};
  const Image img = render(p);
  // A 2 px border of the image is untouched white.
  for (int x = 0; x < p.width; ++x)
    for (int y : {0, 1, p.height - 2, p.height - 1}) ASSERT_TRUE(is_white(img.at(x, y))) << x << "," << y;
  for (int y = 0; y < p.height; ++y)
    for (int x : {0, 1, p.width - 2, p.width - 1}) ASSERT_TRUE(is_white(img.at(x, y))) << x << "," << y;
}

TEST(Plot, AutomaticRangeCoversDataAndBand) {
  ff::LinePlot p;
  p.series = {line({0, 1, 2}, {0.1, 0.9, NAN})};
  p.hlines = {{1.02, "+2 %"}, {0.98, ""}};
  const ff::PlotFrame f = ff::line_plot_frame(p);
  EXPECT_LT(f.x_lo, 0);
  EXPECT_GT(f.x_hi, 1);
  EXPECT_LT(f.x_hi, 1.2);  // x = 2 has no finite y and does not count
  EXPECT_LT(f.y_lo, 0.1);
  EXPECT_GT(f.y_hi, 1.02);
  EXPECT_LT(f.y_hi, 1.2);
}

TEST(Plot, MismatchedSeriesThrows) {
  ff::LinePlot p;
  p.series = {line({0, 1, 2}, {0, 1})};
  EXPECT_THROW(ff::render_line_plot_rgb(p), std::invalid_argument);
}

TEST(Plot, WritesPngAtomically) {
  TempDir dir;
  ff::LinePlot p;
  p.title = "png";
  p.width = 900, p.height = 500;
  p.series = {line({0, 1, 2}, {0, 1, 0})};
  const std::string png = (dir.path / "plot.png").string();
  ff::render_line_plot(p, png);
  ASSERT_TRUE(std::filesystem::exists(png));
  EXPECT_FALSE(std::filesystem::exists(png + ".tmp"));
  const cv::Mat img = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 900);
  EXPECT_EQ(img.rows, 500);
  // Overwriting an existing plot works the same way.
  p.width = 700;
  ff::render_line_plot(p, png);
  EXPECT_EQ(cv::imread(png, cv::IMREAD_COLOR).cols, 700);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 1);
}

TEST(Plot, UnwritablePathThrowsNamingThePath) {
  TempDir dir;
  ff::LinePlot p;
  p.series = {line({0, 1}, {0, 1})};
  const std::string png = (dir.path / "no_such_dir" / "plot.png").string();
  try {
    ff::render_line_plot(p, png);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(png + ".tmp"));
  EXPECT_FALSE(std::filesystem::exists(png));
}

}  // namespace
