// Tests of the arm animation: the deflection exaggeration, frame rendering, the video file.
#include "plotting/animate.hpp"

#include "tests/plotting/test_support.hpp"

#include <gtest/gtest.h>
// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#pragma GCC diagnostic pop

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using ff::test::Image;
using ff::test::near;
using ff::test::TempDir;

// Radial and lateral components of (x, y) for hub angle th.
std::pair<double, double> components(double x, double y, double th) {
  return {x * std::cos(th) + y * std::sin(th), -x * std::sin(th) + y * std::cos(th)};
}

TEST(Animate, ExaggerationKeepsRadialAndScalesLateral) {
  const double th = 0.7;
  const std::vector<std::pair<double, double>> points{{1, 0}, {0.3, 2.1}, {-1.5, 0.4}, {2.2, -0.9}, {0, 0}};
  for (double factor : {1.0, 10.0, 0.25, -2.0}) {
    for (auto [x0, y0] : points) {
      double x = x0, y = y0;
      ff::exaggerate_point(x, y, th, factor);
      const auto [r0, l0] = components(x0, y0, th);
      const auto [r1, l1] = components(x, y, th);
      EXPECT_NEAR(r1, r0, 1e-12) << factor;
      EXPECT_NEAR(l1, factor * l0, 1e-12) << factor;
    }
  }
  // Factor 1 is the identity; a point on the radial line does not move for any factor.
  double x = 0.3, y = 2.1;
  ff::exaggerate_point(x, y, th, 1.0);
  EXPECT_NEAR(x, 0.3, 1e-15);
  EXPECT_NEAR(y, 2.1, 1e-15);
  x = 3 * std::cos(th), y = 3 * std::sin(th);
  ff::exaggerate_point(x, y, th, 25.0);
  EXPECT_NEAR(x, 3 * std::cos(th), 1e-12);
  EXPECT_NEAR(y, 3 * std::sin(th), 1e-12);
}

// A beam of n segments of length `seg` at hub angle th, bent by lateral offsets d_k = c·k².
ff::ArmFrame bent_arm(double t, double th, double c, int n = 6, double seg = 0.5) {
  ff::ArmFrame f{t, {0}, {0}};
  for (int k = 1; k <= n; ++k) {
    const double r = k * seg, l = k == 1 ? 0 : c * (k - 1) * (k - 1);  // the first segment rides with the hub
    f.x.push_back(r * std::cos(th) - l * std::sin(th));
    f.y.push_back(r * std::sin(th) + l * std::cos(th));
  }
  return f;
}

TEST(Animate, FrameExaggerationUsesTheHubAngle) {
  const double th = 1.1;
  const ff::ArmFrame f = bent_arm(0.5, th, 0.01);
  EXPECT_NEAR(ff::arm_hub_angle(f), th, 1e-12);  // direction of the first segment
  ff::ArmFrame g = f;
  g.hub_angle = 0.3;
  EXPECT_DOUBLE_EQ(ff::arm_hub_angle(g), 0.3);  // explicit wins
  const ff::ArmFrame e = ff::exaggerate_frame(f, 10);
  EXPECT_NEAR(e.hub_angle, th, 1e-12);
  EXPECT_DOUBLE_EQ(e.t, 0.5);
  ASSERT_EQ(e.x.size(), f.x.size());
  for (size_t k = 0; k < f.x.size(); ++k) {
    const auto [r0, l0] = components(f.x[k], f.y[k], th);
    const auto [r1, l1] = components(e.x[k], e.y[k], th);
    EXPECT_NEAR(r1, r0, 1e-12) << k;        // radial distances kept
    EXPECT_NEAR(l1, 10 * l0, 1e-12) << k;   // lateral offsets scaled exactly
  }
  // A straight beam stays straight (and unchanged).
  const ff::ArmFrame s = bent_arm(0, th, 0.0);
  const ff::ArmFrame se = ff::exaggerate_frame(s, 50);
  for (size_t k = 0; k < s.x.size(); ++k) {
    EXPECT_NEAR(se.x[k], s.x[k], 1e-12);
    EXPECT_NEAR(se.y[k], s.y[k], 1e-12);
  }
  EXPECT_THROW(ff::arm_hub_angle(ff::ArmFrame{0, {}, {}}), std::invalid_argument);
}

// A slew from 0 to 90° over 40 frames with a decaying lateral vibration.
ff::Animation slew(int frames = 40) {
  ff::Animation a;
  a.title = "slew";
  a.width = 480, a.height = 400;
  a.exaggeration = 5;
  for (int k = 0; k < frames; ++k) {
    const double t = k / a.fps, u = std::min(1.0, double(k) / (frames - 10));
    const double th = std::numbers::pi / 2 * (3 * u * u - 2 * u * u * u);
    a.frames.push_back(bent_arm(t, th, 0.004 * std::sin(5 * t) * std::exp(-t)));
  }
  return a;
}

int count_colour(const Image& img, ff::Rgb c, int tol = 30) {
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) n += near(img.at(x, y), c, tol);
  return n;
}

TEST(Animate, FramesShowArmPayloadAndTrace) {
  ff::Animation a = slew();
  const Image first{a.width, a.height, ff::render_animation_frame(a, 0)};
  const Image last{a.width, a.height, ff::render_animation_frame(a, int(a.frames.size()) - 1)};
  ASSERT_EQ(first.rgb.size(), size_t(a.width) * a.height * 3);
  EXPECT_NE(first.rgb, last.rgb);
  const ff::Rgb arm = ff::palette_colour(0), payload = ff::palette_colour(1), trace = ff::palette_colour(2);
  EXPECT_GT(count_colour(first, arm), 300);
  EXPECT_GT(count_colour(first, payload), 80);
  // The tip path grows: only the legend sample at the start, a quarter circle at the end.
  const int trace_start = count_colour(first, trace), trace_end = count_colour(last, trace);
  EXPECT_GT(trace_end, trace_start + 150);
  a.tip_trace = false;
  EXPECT_LT(count_colour(Image{a.width, a.height, ff::render_animation_frame(a, int(a.frames.size()) - 1)}, trace), 5);
  EXPECT_THROW(ff::render_animation_frame(a, -1), std::out_of_range);
  EXPECT_THROW(ff::render_animation_frame(a, int(a.frames.size())), std::out_of_range);
}

// Whether two renders differ above the bottom band (where the "deflection x N" note goes).
bool view_differs(const ff::Animation& a, const ff::Animation& b, int k) {
  const auto p = ff::render_animation_frame(a, k), q = ff::render_animation_frame(b, k);
  const size_t rows = size_t(a.height) * 85 / 100;
  return !std::equal(p.begin(), p.begin() + long(rows * size_t(a.width) * 3), q.begin());
}

TEST(Animate, ExaggerationChangesOnlyBentArms) {
  ff::Animation a = slew(12);
  for (auto& f : a.frames) f = bent_arm(f.t, 0.4, 0.0);  // straight beam
  ff::Animation b = a;
  b.exaggeration = 8;
  EXPECT_FALSE(view_differs(a, b, 5));
  for (auto* anim : {&a, &b})
    for (auto& f : anim->frames) f = bent_arm(f.t, 0.4, 0.01);
  EXPECT_TRUE(view_differs(a, b, 5));
}

// Mean absolute difference of two equally sized BGR images.
double mean_diff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  const cv::Scalar m = cv::mean(d);
  return (m[0] + m[1] + m[2]) / 3;
}

cv::Mat bgr_frame(const ff::Animation& a, int k) {
  std::vector<unsigned char> rgb = ff::render_animation_frame(a, k);
  cv::Mat m(a.height, a.width, CV_8UC3, rgb.data()), out;
  cv::cvtColor(m, out, cv::COLOR_RGB2BGR);
  return out;
}

// `tolerance`: mean difference allowed between a decoded frame and the rendered one (codec loss).
void expect_video(const ff::Animation& a, const std::string& path, double tolerance) {
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  EXPECT_GT(std::filesystem::file_size(path), 1000u) << path;
  cv::VideoCapture in(path, cv::CAP_FFMPEG);
  ASSERT_TRUE(in.isOpened()) << path;
  EXPECT_EQ(int(in.get(cv::CAP_PROP_FRAME_WIDTH)), a.width);
  EXPECT_EQ(int(in.get(cv::CAP_PROP_FRAME_HEIGHT)), a.height);
  EXPECT_NEAR(in.get(cv::CAP_PROP_FPS), a.fps, 1e-6);
  std::vector<cv::Mat> frames;
  for (cv::Mat m; in.read(m);) frames.push_back(m.clone());
  ASSERT_EQ(frames.size(), a.frames.size()) << path;
  EXPECT_EQ(frames[0].cols, a.width);
  EXPECT_EQ(frames[0].rows, a.height);
  // Frame 20 of the video is frame 20 of the animation (up to compression), not frame 5.
  const cv::Mat want = bgr_frame(a, 20);
  EXPECT_LT(mean_diff(frames[20], want), tolerance) << path;
  EXPECT_GT(mean_diff(frames[5], want), mean_diff(frames[20], want) + 0.3) << path;
}

TEST(Animate, WritesMjpgAvi) {
  TempDir dir;
  const ff::Animation a = slew();
  const std::string path = (dir.path / "arm.avi").string();
  ff::render_animation(a, path);
  expect_video(a, path, 2.0);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 1);  // no temporary left
  // Overwriting works the same way.
  ff::render_animation(a, path);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 1);
}

TEST(Animate, WritesMp4) {
  TempDir dir;
  const ff::Animation a = slew();
  const std::string path = (dir.path / "arm.mp4").string();
  ff::render_animation(a, path);
  expect_video(a, path, 6.0);  // mp4v at its default bit rate is lossier than Motion-JPEG
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 1);
}

TEST(Animate, UnwritablePathThrowsNamingThePath) {
  TempDir dir;
  const std::string path = (dir.path / "no_such_dir" / "arm.avi").string();
  try {
    ff::render_animation(slew(5), path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 0);
}

TEST(Animate, RejectsBadInput) {
  ff::Animation a = slew(5);
  ff::Animation none = a;
  none.frames.clear();
  EXPECT_THROW(ff::render_animation_frame(none, 0), std::out_of_range);
  EXPECT_THROW(ff::render_animation(none, "/tmp/never.avi"), std::invalid_argument);
  ff::Animation odd = a;
  odd.frames[2].y.pop_back();
  EXPECT_THROW(ff::render_animation_frame(odd, 0), std::invalid_argument);
  ff::Animation slow = a;
  slow.fps = 0;
  EXPECT_THROW(ff::render_animation_frame(slow, 0), std::invalid_argument);
  ff::Animation nan = a;
  nan.frames[1].x[3] = NAN;
  EXPECT_THROW(ff::render_animation_frame(nan, 0), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists("/tmp/never.avi"));
}

}  // namespace
