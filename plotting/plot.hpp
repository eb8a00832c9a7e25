// Plotting library: line plots rendered to PNG with OpenCV (which stays out of this header).
// Axes with 1-2-5 ticks, grid, labels, title, legend, colour-blind-friendly palette (Okabe-Ito).
// Text goes through OpenCV's Hershey font, which is ASCII only: common UTF-8 signs in labels
// (·, ±, °, µ, ², −, Greek letters) are spelled out in ASCII, anything else becomes '?'.
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace ff {

struct Rgb {
  unsigned char r, g, b;
};

// i-th colour of the palette (Okabe-Ito, ordered for a white background); wraps, negative i too.
Rgb palette_colour(int i);
// Number of distinct colours before palette_colour wraps.
int palette_size();

// "Nice" tick positions inside [lo, hi] (ends included) with about `target` ticks, step 1, 2 or
// 5 × 10^k. Always at least two ticks: lo == hi is widened around the value first.
// Throws std::invalid_argument if lo or hi is not finite.
std::vector<double> calc_nice_ticks(double lo, double hi, int target = 6);
// Step between consecutive ticks of calc_nice_ticks(lo, hi, target).
double nice_tick_step(double lo, double hi, int target = 6);

// Tick label text for `value` on an axis whose ticks are `step` apart. The number of decimals
// follows from the step, so all labels of one axis share it ("0.2", "0.4", "1.0"); zero is
// always "0". Steps >= 1e5 or < 1e-4 use exponent form ("1e+05", "2.5e-05").
std::string format_tick(double value, double step);

struct Series {
  std::string label;              // legend text; empty = not in the legend
  std::vector<double> x, y;       // same length; NaN breaks the line
  int colour = -1;                // palette index; -1 = next in order
  double width = 2.0;             // px at 1400 × 800; scales with the image like the text
  bool dashed = false;
  bool line = true;               // false: markers only
  // Drawn at every finite point; kBound: a lower bound (draw_bound_marker; e.g. a settling time of runs
  // that did not settle, at their horizon), its legend swatch the marker when there is no line.
  enum class Marker { kNone, kDot, kCross, kBound } marker = Marker::kNone;
};

// Horizontal reference line drawn dark grey across the plot, e.g. one edge of a ±2 % settling
// band; listed in the legend if it has a label. Its y is included in the automatic y range.
struct HLine {
  double y;
  std::string label;
  bool dashed = true;
};

struct LinePlot {
  std::string title, x_label, y_label;          // labels carry units, e.g. "time (s)", "tip angle (rad)"
  std::vector<Series> series;
  std::vector<HLine> hlines;
  int width = 1400, height = 800;               // px, at least 320 × 240
  // optional fixed ranges; NaN = automatic from data with a small margin
  double x_min = NAN, x_max = NAN, y_min = NAN, y_max = NAN;
  std::vector<double> x_ticks;                  // fixed x ticks (e.g. version numbers); empty = automatic
  std::vector<std::string> x_tick_labels;       // their text (e.g. "2 +coulomb"); empty = the numbers
};

// Where the data lands in the image: the plot area is the pixels [left, left + width) ×
// [top, top + height); x_lo maps to column left, x_hi to column left + width - 1, y_hi to row
// top, y_lo to row top + height - 1. The frame is drawn just outside this area.
struct PlotFrame {
  int left = 0, top = 0, width = 0, height = 0;   // px
  double x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;  // data range shown
  double x_to_px(double x) const { return left + (x - x_lo) / (x_hi - x_lo) * (width - 1); }
  double y_to_px(double y) const { return top + (y_hi - y) / (y_hi - y_lo) * (height - 1); }
};

// The frame render_line_plot will use for `plot` (same layout, nothing drawn).
PlotFrame line_plot_frame(const LinePlot& plot);

// Renders to a PNG file. Throws std::runtime_error naming the path if it cannot be written.
// Writes atomically: render to an exclusive temporary beside it and rename, so a killed run never leaves half a PNG.
// Throws std::invalid_argument for a series whose x and y differ in length, or a too small size.
void render_line_plot(const LinePlot& plot, const std::string& png_path);
// Same, into an RGB buffer (row-major, 3 bytes per pixel, width × height), for tests and composing.
std::vector<unsigned char> render_line_plot_rgb(const LinePlot& plot);

}  // namespace ff
