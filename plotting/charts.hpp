// Chart kinds for sweep and uncertainty results, rendered to PNG with OpenCV (which stays out of
// this header), in the style of plot.hpp (same palette, fonts, axes, legend, atomic writes):
//   HeatMap    a response over two parameters (viridis cells, colour bar, NaN cells hatched grey)
//   BandPlot   percentile bands (e.g. p5..p95, translucent) under their median lines
//   Histogram  counts of a sample (Freedman–Diaconis bins by default) or its empirical CDF
//   BarChart   grouped bars with error whiskers, e.g. Sobol' first/total indices per parameter
// Every render_* throws std::runtime_error naming the path if the PNG cannot be written (it is
// written to an exclusive temporary beside it and renamed), and std::invalid_argument for inconsistent input or an
// image smaller than 320 × 240. The *_rgb variants return the pixels and where the data landed.
#pragma once

#include "plotting/plot.hpp"

#include <string>
#include <vector>

namespace ff {

struct HeatMap {
  std::string title, x_label, y_label, value_label;  // value_label on the colour bar, with units
  std::vector<double> x, y;    // cell centres (ascending), sizes nx, ny; drawn as equal cells labelled by centre
  std::vector<double> values;  // ny × nx row-major (values[iy*nx + ix]); NaN = cell hatched grey, "n/a" in the bar
  std::vector<char> bounds;    // empty, or as values: 1 = the value is a lower bound (runs not settled, counted at
                               // their horizon): "> v" in the cell and the bound marker in its corner
  bool annotate = true;        // print each cell's value when the cells are large enough
  int width = 1200, height = 900;
};
void render_heat_map(const HeatMap& m, const std::string& png_path);

struct BandSeries {
  std::string label;
  std::vector<double> x, mid, lo, hi;  // same length; NaN breaks line and band
  int colour = -1;                     // palette index; -1 = next in order
  std::vector<double> bound_x, bound_y;  // points of the lines that are lower bounds (a percentile above the
                                         // horizon, drawn at it): the bound marker each
  std::string bound_label;               // their legend entry ("" = none)
};
struct BandPlot {
  std::string title, x_label, y_label;
  std::vector<BandSeries> series;
  int width = 1400, height = 800;
};
void render_band_plot(const BandPlot& p, const std::string& png_path);

struct Histogram {
  std::string title, x_label;
  std::vector<double> values;               // NaN/inf are not binned but counted and reported in the title
  int bins = 0;                             // 0 = Freedman–Diaconis
  std::vector<double> markers;              // vertical dashed lines, e.g. a spec limit, p95
  std::vector<std::string> marker_labels;   // legend text per marker (missing/empty = not in the legend)
  int width = 1200, height = 800;
  std::string nan_label = "not finite";     // title note "(12 of 500 <nan_label>)", e.g. "not settled"
  bool nan_bar = false;                     // show the NaN/inf values as mass of their own (e.g. right-censored
                                            // settling times): a bar and a CDF that stops short of 1, below
};
// Count axis on the left; bars over equal bins from the smallest to the largest finite value. With
// nan_bar, the NaN/inf values are one more bar, hatched grey, half a bar gap right of the bins (as
// wide as a bin, at least 1/12 of their range; "<nan_label>: k" in the legend).
void render_histogram(const Histogram& h, const std::string& png_path);
// Empirical CDF of the finite values as a step plot, y in [0, 1]; markers as vertical dashed lines.
// With nan_bar, the fractions are of every value, so the curve stops at 1 - (NaN/inf fraction), and
// the mass above it is shaded grey right of the largest value ("<nan_label>: k of n" in the legend).
void render_cdf(const Histogram& h, const std::string& png_path);

struct BarChart {
  std::string title, y_label;
  std::vector<std::string> names;                 // categories along x
  std::vector<std::vector<double>> groups;        // groups[g][i]: bar of group g for names[i]; NaN = "n/a"
  std::vector<std::string> group_labels;          // legend text per group
  std::vector<std::vector<double>> errors;        // optional whisker half-widths, same shape as groups
  int width = 1200, height = 800;
};
// Grouped bars from zero (palette colour g for group g) with error whiskers. Category i spans
// x = i − 0.5 .. i + 0.5; with G groups, bar g is centred at i + (g − (G−1)/2)·0.8/G, 0.8/G wide.
void render_bar_chart(const BarChart& b, const std::string& png_path);

// ---------------------------------------------------------------- helpers (exposed for tests)

// Equal-width bins over [lo, lo + bins·width]: bin i holds lo + i·width <= v < lo + (i+1)·width,
// the last bin also its upper edge.
struct HistogramBins {
  double lo = 0, width = 1;
  std::vector<int> counts;
  int not_finite = 0;  // NaN/inf values, not binned
  double edge(size_t i) const { return lo + double(i) * width; }
};
// Bins from the smallest to the largest finite value (a range of zero is widened to ±0.5).
// bins = 0 takes freedman_diaconis_bins. No finite values gives no bins.
// Throws std::invalid_argument for bins < 0.
HistogramBins calc_histogram_bins(const std::vector<double>& values, int bins = 0);
// Freedman–Diaconis: ceil(range / (2·IQR·n^(-1/3))) over the finite values, clamped to 1..200;
// Sturges (ceil(log2 n) + 1) when the IQR is zero. 1 for fewer than two finite values.
int freedman_diaconis_bins(const std::vector<double>& values);

// Empirical CDF of the finite values: x ascending and distinct, p[i] = fraction of values <= x[i].
struct Ecdf {
  std::vector<double> x, p;
};
Ecdf calc_ecdf(const std::vector<double>& values);

// Viridis colour at t in [0, 1] (clamped): dark purple at 0, yellow at 1.
Rgb viridis_colour(double t);

// A chart rendered into memory, with where its data landed.
struct ChartImage {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  // row-major, 3 bytes per pixel
  PlotFrame frame;                 // plot area and data range; a heat map's x/y are cell indices
                                   // (cell ix spans ix - 0.5 .. ix + 0.5), a bar chart's x the category index
  PlotFrame colour_bar;            // heat map only: the bar's pixels, y_lo..y_hi = value min..max
};
ChartImage render_heat_map_rgb(const HeatMap& m);
ChartImage render_band_plot_rgb(const BandPlot& p);
ChartImage render_histogram_rgb(const Histogram& h);
ChartImage render_cdf_rgb(const Histogram& h);
ChartImage render_bar_chart_rgb(const BarChart& b);

}  // namespace ff
