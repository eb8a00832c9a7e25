// Top view video of the arm, drawn with the shared pieces of canvas.hpp, written by canvas::write_video.
#include "plotting/animate.hpp"

#include "plotting/canvas.hpp"

#include <array>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace ff {
namespace {

using namespace canvas;

// ---------------------------------------------------------------- checks and geometry

void validate(const Animation& a) {
  check_image_size("Animation", a.width, a.height, 240, 240);
  if (a.frames.empty()) throw std::invalid_argument("Animation: no frames");
  if (!(a.fps > 0) || !std::isfinite(a.fps)) throw std::invalid_argument("Animation: fps must be > 0");
  if (!std::isfinite(a.exaggeration)) throw std::invalid_argument("Animation: exaggeration must be finite");
  for (size_t k = 0; k < a.frames.size(); ++k) {
    const ArmFrame& f = a.frames[k];
    if (f.x.empty() || f.x.size() != f.y.size())
      throw std::invalid_argument("Animation: frame " + std::to_string(k) + " has " + std::to_string(f.x.size()) +
                                  " x and " + std::to_string(f.y.size()) + " y values");
    for (size_t i = 0; i < f.x.size(); ++i)
      if (!std::isfinite(f.x[i]) || !std::isfinite(f.y[i]))
        throw std::invalid_argument("Animation: frame " + std::to_string(k) + " (t = " + std::to_string(f.t) +
                                    " s) has a non-finite point " + std::to_string(i));
  }
}

// Undeformed length from the hub axis: |p0| + the segment lengths.
double beam_length(const ArmFrame& f) {
  double len = std::hypot(f.x[0], f.y[0]);
  for (size_t i = 1; i < f.x.size(); ++i) len += std::hypot(f.x[i] - f.x[i - 1], f.y[i] - f.y[i - 1]);
  return len;
}

// The view: world metres → image pixels, the same for every frame.
struct View {
  Style st;
  cv::Rect area;                        // px where the world is drawn
  double scale = 1, cx = 0, cy = 0;     // px per m; world point at the area's centre
  double bar_m = 1;                     // scale bar (and grid) step, m
  std::vector<ArmFrame> shown;          // frames as drawn (exaggerated), with their hub angle set
  std::vector<double> length;           // undeformed length per frame, m
  cv::Point legend_at;
  std::vector<LegendEntry> legend;
  cv::Point2d px(double x, double y) const {
    return {area.x + area.width / 2.0 + (x - cx) * scale, area.y + area.height / 2.0 - (y - cy) * scale};
  }
};

// Bottom band height: the scale bar row.
int bottom_band(const Style& st) { return st.gap + line_height(st.label) + st.pad; }

// Top band height: title row, then the time stamp row.
int top_band(const Animation& a, const Style& st) {
  return st.pad + (a.title.empty() ? 0 : line_height(st.title) + st.gap) + line_height(st.label) + st.gap;
}

std::vector<LegendEntry> legend_entries(const Animation& a, const Style& st) {
  std::vector<LegendEntry> e{{"arm", {bgr(palette_colour(0)), st.px(6), false}},
                             {"undeformed", {kRefLineColour, st.px(2), true}},
                             {"payload", {bgr(palette_colour(1)), 1, false}, Swatch::box}};
  if (a.tip_trace) e.push_back({"tip path", {bgr(palette_colour(2)), std::max(2, st.px(2)), false}});
  return e;
}

// The legend's corner of the view that the arm visits least over the whole video (points and
// points along the segments, all frames), so the legend stays put and covers little.
cv::Point legend_corner(const View& v, cv::Size box) {
  const int inset = v.st.px(10), reach = v.st.px(20);  // reach: arm thickness and payload around a point
  const int l = v.area.x + inset, r = v.area.x + v.area.width - inset - box.width;
  const int t = v.area.y + inset, b = v.area.y + v.area.height - inset - box.height;
  const std::array<cv::Point, 4> corners{{{r, b}, {l, b}, {r, t}, {l, t}}};  // preferred order on ties
  std::array<cv::Rect2d, 4> zones;
  for (size_t c = 0; c < 4; ++c)
    zones[c] = cv::Rect2d(corners[c].x - reach, corners[c].y - reach, box.width + 2.0 * reach, box.height + 2.0 * reach);
  std::array<long, 4> hits{};
  for (const auto& f : v.shown)
    for (size_t i = 0; i < f.x.size(); ++i) {
      const double x0 = i == 0 ? 0 : f.x[i - 1], y0 = i == 0 ? 0 : f.y[i - 1];  // segment i from the point before
      for (int s = 1; s <= 8; ++s) {
        const cv::Point2d p = v.px(x0 + (f.x[i] - x0) * s / 8.0, y0 + (f.y[i] - y0) * s / 8.0);
        for (size_t c = 0; c < 4; ++c) hits[c] += zones[c].contains(p);
      }
    }
  return corners[size_t(std::min_element(hits.begin(), hits.end()) - hits.begin())];
}

View make_view(const Animation& a) {
  validate(a);
  View v;
  v.st = style_at(std::clamp(std::min(a.width, a.height) / 800.0, 0.45, 4.0));
  const int top = top_band(a, v.st);
  v.area = cv::Rect(v.st.pad, top, a.width - 2 * v.st.pad, std::max(10, a.height - top - bottom_band(v.st)));
  double xlo = 0, xhi = 0, ylo = 0, yhi = 0;  // the hub is always in view
  for (const auto& f : a.frames) {
    ArmFrame s = exaggerate_frame(f, a.exaggeration);
    const double len = beam_length(f);
    extend(xlo, xhi, s.x), extend(ylo, yhi, s.y);
    extend(xlo, xhi, {len * std::cos(s.hub_angle)}), extend(ylo, yhi, {len * std::sin(s.hub_angle)});
    v.shown.push_back(std::move(s));
    v.length.push_back(len);
  }
  const double extent = std::max({xhi - xlo, yhi - ylo, 1e-3});
  const double margin = 0.08 * extent;
  xlo -= margin, xhi += margin, ylo -= margin, yhi += margin;
  v.scale = std::min(v.area.width / (xhi - xlo), v.area.height / (yhi - ylo));
  v.cx = (xlo + xhi) / 2, v.cy = (ylo + yhi) / 2;
  v.bar_m = nice_ticks(0, 0.25 * v.area.width / v.scale, 2).step;
  v.legend = legend_entries(a, v.st);
  v.legend_at = legend_corner(v, legend_size(v.legend, v.st));
  return v;
}

// ---------------------------------------------------------------- drawing

// Light grid at multiples of the scale bar step.
void draw_world_grid(cv::Mat& img, const View& v) {
  const double x0 = v.cx - v.area.width / 2.0 / v.scale, x1 = v.cx + v.area.width / 2.0 / v.scale;
  const double y0 = v.cy - v.area.height / 2.0 / v.scale, y1 = v.cy + v.area.height / 2.0 / v.scale;
  for (double x = std::ceil(x0 / v.bar_m) * v.bar_m; x <= x1; x += v.bar_m) {
    const int X = int(std::lround(v.px(x, 0).x));
    cv::line(img, {X, v.area.y}, {X, v.area.y + v.area.height - 1}, kGridColour, 1);
  }
  for (double y = std::ceil(y0 / v.bar_m) * v.bar_m; y <= y1; y += v.bar_m) {
    const int Y = int(std::lround(v.px(0, y).y));
    cv::line(img, {v.area.x, Y}, {v.area.x + v.area.width - 1, Y}, kGridColour, 1);
  }
}

// Payload: a square at the tip, turned with the last segment.
void draw_payload(cv::Mat& img, const View& v, const ArmFrame& f) {
  const size_t n = f.x.size();
  const double angle = n >= 2 ? std::atan2(f.y[n - 1] - f.y[n - 2], f.x[n - 1] - f.x[n - 2]) : f.hub_angle;
  const cv::Point2d c = v.px(f.x[n - 1], f.y[n - 1]);
  const double h = v.st.px(13);
  // Image y points down, so the world angle turns the other way.
  const cv::Point2d u(std::cos(angle) * h, -std::sin(angle) * h), w(-u.y, u.x);
  const std::vector<cv::Point> corners{fixed_point(c + u + w), fixed_point(c - u + w), fixed_point(c - u - w),
                                       fixed_point(c + u - w)};
  cv::fillConvexPoly(img, corners, bgr(palette_colour(1)), cv::LINE_AA, kShift);
  cv::polylines(img, corners, true, kTextColour, 1, cv::LINE_AA, kShift);
}

void draw_arm(cv::Mat& img, const View& v, const ArmFrame& f, double length) {
  const Style& st = v.st;
  // Undeformed radial line, dashed, from the hub axis.
  const cv::Point2d hub = v.px(0, 0);
  const cv::Point2d end = v.px(length * std::cos(f.hub_angle), length * std::sin(f.hub_angle));
  draw_stroke(img, {hub, end}, {kRefLineColour, st.px(2), true}, st);
  // Segments from the hub axis (or the first point) to the tip.
  Polyline arm;
  if (std::hypot(f.x[0], f.y[0]) > 0) arm.push_back(hub);
  for (size_t i = 0; i < f.x.size(); ++i) arm.push_back(v.px(f.x[i], f.y[i]));
  draw_solid(img, arm, bgr(palette_colour(0)), st.px(6));
  // Hub, joints, payload.
  cv::circle(img, fixed_point(hub), st.px(17) * 16, kFrameColour, cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(img, fixed_point(hub), st.px(5) * 16, kWhite, cv::FILLED, cv::LINE_AA, kShift);
  for (size_t i = 1; i + 1 < f.x.size(); ++i)
    cv::circle(img, fixed_point(v.px(f.x[i], f.y[i])), st.px(5) * 16, kTextColour, cv::FILLED, cv::LINE_AA, kShift);
  draw_payload(img, v, f);
}

// Scale bar "|——| 0.5 m" bottom left, the exaggeration bottom right.
void draw_scale(cv::Mat& img, const View& v, const Animation& a) {
  const Style& st = v.st;
  const int y = img.rows - st.pad - line_height(st.label) / 2, x0 = st.pad;
  const int x1 = x0 + int(std::lround(v.bar_m * v.scale)), th = st.px(3), cap = st.px(7);
  cv::line(img, {x0, y}, {x1, y}, kTextColour, th);
  cv::line(img, {x0, y - cap}, {x0, y + cap}, kTextColour, th);
  cv::line(img, {x1, y - cap}, {x1, y + cap}, kTextColour, th);
  put_text(img, format_tick(v.bar_m, v.bar_m) + " m", {x1 + st.gap + cap, y}, HAlign::left, VAlign::middle, st.label,
           kTextColour);
  if (a.exaggeration != 1) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "deflection x %g", a.exaggeration);
    put_text(img, buf, {img.cols - st.pad, y}, HAlign::right, VAlign::middle, st.label, kTextColour);
  }
}

// Title on top, time stamp below it on the left (left-aligned, so it does not jitter).
void draw_header(cv::Mat& img, const View& v, const Animation& a, const ArmFrame& f) {
  const Style& st = v.st;
  int y = st.pad;
  const std::string title = hershey_text(a.title);
  if (!title.empty()) {
    put_text(img, title, {img.cols / 2, y}, HAlign::centre, VAlign::top, fitted(title, st.title, img.cols - 2 * st.pad),
             kTextColour);
    y += line_height(st.title) + st.gap;
  }
  const int decimals = std::clamp(int(std::ceil(std::log10(a.fps) - 1e-9)), 1, 4);
  char buf[64];
  std::snprintf(buf, sizeof buf, "t = %.*f s", decimals, f.t);
  put_text(img, buf, {st.pad, y}, HAlign::left, VAlign::top, st.label, kTextColour);
}

cv::Mat frame_bgr(const Animation& a, const View& v, size_t k) {
  cv::Mat img(a.height, a.width, CV_8UC3, kWhite);
  {
    cv::Mat roi = img(v.area);  // world drawing clipped to the view
    cv::Mat world(img.size(), img.type(), kWhite);
    draw_world_grid(world, v);
    if (a.tip_trace && k > 0) {
      Polyline trace;
      for (size_t j = 0; j <= k; ++j) trace.push_back(v.px(v.shown[j].x.back(), v.shown[j].y.back()));
      draw_solid(world, trace, bgr(palette_colour(2)), std::max(2, v.st.px(2)));
    }
    draw_arm(world, v, v.shown[k], v.length[k]);
    world(v.area).copyTo(roi);
  }
  cv::rectangle(img, {v.area.x - 1, v.area.y - 1}, {v.area.x + v.area.width, v.area.y + v.area.height}, kLegendBorder,
                1);
  draw_legend_at(img, v.legend_at, v.legend, v.st);
  draw_header(img, v, a, v.shown[k]);
  draw_scale(img, v, a);
  return img;
}

}  // namespace

// ---------------------------------------------------------------- public API

double arm_hub_angle(const ArmFrame& f) {
  if (std::isfinite(f.hub_angle)) return f.hub_angle;
  if (f.x.empty() || f.y.empty()) throw std::invalid_argument("arm_hub_angle: empty frame");
  if (f.x.size() < 2 || f.y.size() < 2) return std::atan2(f.y[0], f.x[0]);
  return std::atan2(f.y[1] - f.y[0], f.x[1] - f.x[0]);
}

void exaggerate_point(double& x, double& y, double hub_angle, double factor) {
  const double c = std::cos(hub_angle), s = std::sin(hub_angle);
  const double radial = x * c + y * s, lateral = (-x * s + y * c) * factor;
  x = radial * c - lateral * s;
  y = radial * s + lateral * c;
}

ArmFrame exaggerate_frame(const ArmFrame& f, double factor) {
  ArmFrame out = f;
  out.hub_angle = arm_hub_angle(f);
  for (size_t i = 0; i < out.x.size() && i < out.y.size(); ++i)
    exaggerate_point(out.x[i], out.y[i], out.hub_angle, factor);
  return out;
}

std::vector<unsigned char> render_animation_frame(const Animation& a, int frame) {
  if (frame < 0 || size_t(frame) >= a.frames.size())
    throw std::out_of_range("render_animation_frame: frame " + std::to_string(frame) + " outside 0.." +
                            std::to_string(int(a.frames.size()) - 1));
  const View v = make_view(a);
  return rgb_bytes(frame_bgr(a, v, size_t(frame)));
}

void render_animation(const Animation& a, const std::string& video_path) {
  const View v = make_view(a);
  write_video("render_animation", video_path, a.fps, cv::Size(a.width, a.height), int(a.frames.size()),
              [&](int k) { return frame_bgr(a, v, size_t(k)); });
}

}  // namespace ff
