// Internal drawing toolkit shared by the plot kinds (line plot, charts, animation): colours, nice
// ticks, text, Style (sizes from the image size), Axes (layout, data→pixel mapping, grid, frame,
// ticks, labels, title), polylines (NaN breaks, clipping, dashes), translucent fills, legend and
// atomic file output. Not part of the public API: it includes OpenCV, which public headers avoid.
#pragma once

#include "plotting/plot.hpp"

// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ff::canvas {

// ---------------------------------------------------------------- colours

cv::Scalar bgr(Rgb c);
// a·(1 − t) + b·t per channel.
cv::Scalar mix(const cv::Scalar& a, const cv::Scalar& b, double t);

// A fixed colour, constant-initialised (cv::Scalar is not a literal type, and a dynamically
// initialised one could still be black when a plot is rendered from another static initialiser).
struct Bgr {
  double b, g, r;
  operator cv::Scalar() const { return {b, g, r}; }
};

inline constexpr Bgr kWhite{255, 255, 255};
inline constexpr Bgr kTextColour{25, 25, 25};
inline constexpr Bgr kTickTextColour{55, 55, 55};
inline constexpr Bgr kFrameColour{70, 70, 70};
inline constexpr Bgr kGridColour{228, 228, 228};
inline constexpr Bgr kRefLineColour{120, 120, 120};
inline constexpr Bgr kLegendBorder{175, 175, 175};

// Palette index per item: explicit ones (>= 0) as given, -1 takes the next index no item claims.
std::vector<int> assign_colours(const std::vector<int>& requested);

// ---------------------------------------------------------------- ticks

struct Ticks {
  std::vector<double> values;
  double step = 1;
  std::vector<std::string> labels;  // text per value; empty = format_tick(value, step)
  std::string label(size_t i) const { return i < labels.size() ? labels[i] : format_tick(values[i], step); }
};

// [lo, hi] ordered and widened when (nearly) empty, so ticks can always be placed.
std::pair<double, double> widened(double lo, double hi);
// Ticks for [lo, hi]: the 1-2-5 step nearest range/(target-1), made smaller until two fit but
// never below `min_step` (e.g. 1 for counts). Throws std::invalid_argument for a non-finite range.
Ticks nice_ticks(double lo, double hi, int target, double min_step = 0);

// ---------------------------------------------------------------- text

// `s` with every non-ASCII UTF-8 sequence replaced by its ASCII spelling, or '?'.
std::string hershey_text(std::string_view s);

struct Font {
  double scale;
  int thickness;
};

// Size of a text: width, height above the baseline, and depth below it.
struct TextSize {
  int width, ascent, descent;
  int height() const { return ascent + descent; }
};

TextSize measure(const std::string& t, const Font& f);
// Height of a line of text with capitals and descenders in font `f`.
int line_height(const Font& f);
// `f` scaled down if needed so `t` fits into `max_width` px.
Font fitted(const std::string& t, Font f, int max_width);

enum class HAlign { left, centre, right };
enum class VAlign { top, middle, bottom };  // top of capitals, middle of capitals, bottom of descenders

// Draws ASCII text `t` anti-aliased, aligned to the point `at`.
void put_text(cv::Mat& img, const std::string& t, cv::Point at, HAlign h, VAlign v, const Font& f,
              const cv::Scalar& colour);
// `t` drawn on a white patch and turned 90° counter-clockwise (reads bottom to top).
cv::Mat rotated_text(const std::string& t, const Font& f, const cv::Scalar& colour);
// Copies `patch` into `img` with its top-left at `tl`, cut to the image.
void paste(cv::Mat& img, const cv::Mat& patch, cv::Point tl);

// ---------------------------------------------------------------- style

// Sizes derived from the image size; everything is designed for scale factor s = 1 (1400 × 800).
struct Style {
  double s;
  Font title, label, tick, legend;
  int pad, gap, tick_len;
  int px(double at_reference) const { return std::max(1, int(std::lround(at_reference * s))); }
};

Style style_at(double s);
// Scale from a 1400 × 800 reference, clamped to 0.6 .. 4.
Style style_for(cv::Size size);

// Throws std::invalid_argument "<what>: size WxH outside 320x240 .. 20000x20000".
void check_image_size(const std::string& what, int width, int height, int min_w = 320, int min_h = 240);

// ---------------------------------------------------------------- axes

struct Range {
  double lo, hi;
};

// Axis range: fixed ends where given, else the data extent (lo/hi; NaN if none) plus `margin` of it.
Range resolve_range(double fixed_lo, double fixed_hi, double data_lo, double data_hi, double margin = 0.04);

// Extent of the finite values of `v` selected by `keep(i)`, folded into [lo, hi].
template <class Keep>
void extend(double& lo, double& hi, const std::vector<double>& v, Keep keep) {
  for (size_t i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && keep(i)) lo = std::min(lo, v[i]), hi = std::max(hi, v[i]);
}
inline void extend(double& lo, double& hi, const std::vector<double>& v) {
  extend(lo, hi, v, [](size_t) { return true; });
}

struct AxesText {
  std::string title, x_label, y_label;  // already ASCII
};

// A 2-D axes box: plot area in image pixels, the data range it shows and the ticks.
struct Axes {
  cv::Rect area;
  Range x, y;
  Ticks x_ticks, y_ticks;
  Font x_font, y_font;  // tick label fonts
  int x_label_rows = 1; // x tick labels alternate over this many rows
  // Data → pixel inside the area (0 = first column/row of the area).
  double ax(double v) const { return (v - x.lo) / (x.hi - x.lo) * (area.width - 1); }
  double ay(double v) const { return (y.hi - v) / (y.hi - y.lo) * (area.height - 1); }
  // Data → image pixel.
  int ix(double v) const { return area.x + int(std::lround(ax(v))); }
  int iy(double v) const { return area.y + int(std::lround(ay(v))); }
  PlotFrame frame() const { return {area.x, area.y, area.width, area.height, x.lo, x.hi, y.lo, y.hi}; }
};

struct AxesOptions {
  // Fixed ticks with their labels (e.g. category names); thinned to every k-th when crowded.
  std::optional<Ticks> x_ticks, y_ticks;
  double x_min_font = 1.0;  // fixed x labels may shrink to this fraction of the tick font before any is dropped
  bool x_stagger = false;   // fixed x labels may alternate over two rows before any is dropped
  int reserve_right = 0;  // px kept free right of the area, e.g. for a colour bar
  double y_min_step = 0;  // smallest automatic y tick step, e.g. 1 for counts
};

// Margins from the text sizes, then ticks for the area that is left.
Axes layout_axes(cv::Size img, Range x, Range y, const AxesText& text, const Style& st, const AxesOptions& opt = {});
// Light grid lines at the x and/or y ticks.
void draw_grid(cv::Mat& img, const Axes& a, bool x_lines = true, bool y_lines = true);
// Frame one pixel outside the area, outward ticks and their labels.
void draw_frame_and_ticks(cv::Mat& img, const Axes& a, const Style& st);
// X label centred under the tick labels; y label rotated, centred left of them; title on top.
void draw_axes_text(cv::Mat& img, const Axes& a, const AxesText& text, const Style& st);

// ---------------------------------------------------------------- polylines and fills

using Polyline = std::vector<cv::Point2d>;

constexpr int kShift = 4;  // sub-pixel bits for OpenCV drawing
inline cv::Point fixed_point(cv::Point2d p) { return {int(std::lround(p.x * 16)), int(std::lround(p.y * 16))}; }

// Pixel-space pieces (relative to the area) of a series: split at NaN/inf and where segments
// leave `clip`. An isolated finite point becomes a one-point piece.
std::vector<Polyline> pieces(const std::vector<double>& x, const std::vector<double>& y, const Axes& a,
                             const cv::Rect2d& clip);

// Solid anti-aliased polyline, or a dot for a one-point piece.
void draw_solid(cv::Mat& img, const Polyline& pl, const cv::Scalar& c, int th);
// Dashed polyline: `on` px drawn, `off` px skipped, the pattern running on across vertices.
void draw_dashed(cv::Mat& img, const Polyline& pl, const cv::Scalar& c, int th, double on, double off);

// Line style shared by plot lines and legend samples.
struct Stroke {
  cv::Scalar colour;
  int thickness;
  bool dashed;
};

void draw_stroke(cv::Mat& img, const Polyline& pl, const Stroke& k, const Style& st);
// Draws a series into `roi` (the plot area), clipped to it.
void draw_series(cv::Mat& roi, const Axes& a, const std::vector<double>& x, const std::vector<double>& y,
                 const Stroke& k, const Style& st);

// A value known only as a lower bound (a settling time of runs that did not settle, drawn at their
// horizon): an upward-pointing open triangle of circumradius r px centred at c, the same in every chart.
void draw_bound_marker(cv::Mat& img, cv::Point2d c, double r, const cv::Scalar& colour, int thickness);

// Fills polygons (pixel coordinates of `img`) blended over the image: alpha·colour + (1 − alpha)·below.
void fill_translucent(cv::Mat& img, const std::vector<Polyline>& polygons, const cv::Scalar& colour, double alpha);

// ---------------------------------------------------------------- legend

enum class Swatch {
  line,   // the stroke
  box,    // a box filled with the stroke colour at `alpha` over white
  band,   // a translucent box (alpha) with the stroke through its middle
  bound,  // the lower-bound marker (draw_bound_marker)
};

struct LegendEntry {
  std::string label;  // ASCII
  Stroke stroke;
  Swatch swatch = Swatch::line;
  double alpha = 1.0;
};

cv::Size legend_size(const std::vector<LegendEntry>& entries, const Style& st);
// Legend box with its top-left corner at `tl`; entries top to bottom.
void draw_legend_at(cv::Mat& img, cv::Point tl, const std::vector<LegendEntry>& entries, const Style& st);
// Legend box in the corner of `area` that covers the least drawn data.
void draw_legend(cv::Mat& img, const cv::Rect& area, const std::vector<LegendEntry>& entries, const Style& st);

// ---------------------------------------------------------------- output

// Writes `bytes` to an exclusive temporary beside `path` and renames it over `path` (common/files.hpp,
// AtomicFile); throws std::runtime_error "<who>: cannot write <path>: why" on failure, leaving no
// temporary file behind.
void write_atomically(const std::string& who, const std::string& path, const std::vector<uchar>& bytes);
// Encodes a BGR image as PNG and writes it atomically.
void write_png(const std::string& who, const cv::Mat& bgr_image, const std::string& path);
// A BGR image as RGB bytes, row-major.
std::vector<unsigned char> rgb_bytes(const cv::Mat& bgr_image);

// ---------------------------------------------------------------- video

// Writes `frames` BGR frames of `size` (frame(k) draws frame k) as a video at `fps`. The container and
// codec follow the extension: ".mp4"/".m4v"/".mov" try mp4v then avc1 (FFmpeg); anything else,
// normally ".avi", is Motion-JPEG in AVI (FFmpeg, then OpenCV's built-in writer); if no mp4 codec
// opens, Motion-JPEG/AVI data goes under the requested name. Written to an exclusive temporary with the
// container's extension beside `path` (AtomicFile) and renamed over `path` when complete. Throws
// std::runtime_error "<who>: cannot write <path>: why" when no file
// can be created there or no codec works, leaving no temporary file behind.
void write_video(const std::string& who, const std::string& path, double fps, cv::Size size, int frames,
                 const std::function<cv::Mat(int)>& frame);

}  // namespace ff::canvas
