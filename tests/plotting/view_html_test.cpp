// Tests of the HTML 3-D viewer (plotting/view_html.hpp): the writer's errors, its atomic write, the scene's
// numbers and escapes in the page, and the page itself in headless Chromium (Debian's chromium, installed
// by scripts/bootstrap): it renders, reports no error, the arm's pixels move between two times and the
// exaggeration bends a deflected capsule. The screenshots are kept in the tests' artefacts/ folder.
#include "plotting/view_html.hpp"

#include "tests/chromium.hpp"
#include "tests/temp_dir.hpp"

#include <gtest/gtest.h>
// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using ff::test::TempDir;
namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;

// A two-capsule arm at height 0.3 m swinging about z through 90 degrees over 2 s (shoulder 0.6 m, forearm
// 0.5 m), its forearm's tip bent down by `droop` m (the rigid ends straight), past a box and above a floor
// plane; `phase` (rad) shifts the swing, for a ghost.
ff::ViewVariant swinging_arm(const std::string& label, double phase, double droop) {
  ff::ViewVariant v;
  v.label = label;
  for (int i = 0; i <= 100; ++i) {
    const double t = 0.02 * i, q = kPi / 2 * t / 2 + phase;
    const float ex = float(std::cos(q)), ey = float(std::sin(q));
    const float elbow[3] = {0.6f * ex, 0.6f * ey, 0.3f}, tip[3] = {1.1f * ex, 1.1f * ey, 0.3f};
    v.t.push_back(t);
    for (auto* a : {&v.ends, &v.rigid_ends}) a->insert(a->end(), {0, 0, 0.3f, elbow[0], elbow[1], elbow[2], elbow[0], elbow[1], elbow[2]});
    v.ends.insert(v.ends.end(), {tip[0], tip[1], tip[2] - float(droop)});
    v.rigid_ends.insert(v.rigid_ends.end(), {tip[0], tip[1], tip[2]});
    v.tool.insert(v.tool.end(), {tip[0], tip[1], tip[2] - float(droop)});
  }
  return v;
}

ff::ViewScene swinging_scene() {
  ff::ViewScene s;
  s.title = "two-link swing";
  ff::ViewShape box, floor;
  box.name = box.type = "box";
  box.pose.topRightCorner<3, 1>() << 0.75, 0.75, 0.2;
  box.size << 0.3, 0.3, 0.4;
  floor.name = "floor", floor.type = "plane";
  floor.pose(2, 3) = -0.05;
  s.shapes = {box, floor};
  // Every other type, behind the arm's swing (x, y < 0): each drawn without a JavaScript error.
  const auto at = [](const std::string& type, double x, double y) {
    ff::ViewShape sh;
    sh.name = sh.type = type;
    sh.pose.topRightCorner<3, 1>() << x, y, 0.2;
    sh.radius = 0.12, sh.length = 0.3;
    return sh;
  };
  for (const char* type : {"sphere", "cylinder", "capsule", "bore"}) s.shapes.push_back(at(type, -0.5, -0.6 + 0.4 * double(s.shapes.size() - 2)));
  ff::ViewShape tetrahedron = at("mesh", -0.9, 0);
  tetrahedron.vertices = {{0, 0, 0}, {0.2f, 0, 0}, {0, 0.2f, 0}, {0, 0, 0.2f}};
  tetrahedron.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  s.shapes.push_back(tetrahedron);
  s.capsules = {{"upper arm", 0.05}, {"forearm", 0.04}};
  s.variants = {swinging_arm("variant 0: nominal", 0, 0.03), swinging_arm("variant 1: ghost", 0.15, 0.03)};
  ff::ViewVariant& v = s.variants[0];
  v.min_clearance = 0.12, v.worst_capsule = 1, v.worst_shape = 0, v.worst_time = 1.0;
  v.worst_a << 0.55, 0.55, 0.3;
  v.worst_b << 0.6, 0.6, 0.3;
  s.variants[1].min_clearance = 0.08;  // the ghost comes closer: the status line says so
  return s;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void expect_invalid(const ff::ViewScene& s, const std::string& fragment) {
  TempDir dir("ff_view_test");
  try {
    ff::write_view_html(s, (dir.path / "v.html").string());
    ADD_FAILURE() << "no error; expected one saying '" << fragment << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.path / "v.html"));
}

TEST(ViewHtml, ASceneWithoutVariantsIsAnError) {
  ff::ViewScene s = swinging_scene();
  s.variants.clear();
  expect_invalid(s, "no variants");
}

TEST(ViewHtml, ArraysNotMatchingTheSamplesAndCapsulesAreErrors) {
  {
    ff::ViewScene s = swinging_scene();
    s.variants[1].ends.pop_back();
    expect_invalid(s, "variant 1 (variant 1: ghost): ends has 1211 values, not 1212 (101 samples x 12)");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.capsules.pop_back();  // the ends now hold 12 values per sample for 6
    expect_invalid(s, "ends has 1212 values, not 606");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.variants[0].rigid_ends.resize(6);
    expect_invalid(s, "rigid_ends has 6 values");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.variants[0].tool.resize(4);
    expect_invalid(s, "tool has 4 values, not 303");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.variants[0].t[7] = s.variants[0].t[6];
    expect_invalid(s, "times must be finite and increasing (sample 7)");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.variants[0].t[3] = std::nan("");
    expect_invalid(s, "times must be finite and increasing (sample 3)");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.variants[0].worst_shape = 7;
    expect_invalid(s, "worst_shape out of range");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.shapes[0].type = "cone";
    expect_invalid(s, "shape 'box': unknown type 'cone'");
  }
  {
    ff::ViewScene s = swinging_scene();
    s.shapes.push_back({.name = "tri", .type = "mesh", .vertices = {{0, 0, 0}, {1, 0, 0}}, .triangles = {{0, 1, 2}}});
    expect_invalid(s, "shape 'tri': triangle index 2 out of range");
  }
}

TEST(ViewHtml, ThePageIsWrittenAtomicallyAndAnUnwritablePathIsNamed) {
  TempDir dir("ff_view_test");
  const fs::path page = dir.path / "view.html";
  ff::write_view_html(swinging_scene(), page.string());
  EXPECT_TRUE(fs::exists(page));
  EXPECT_FALSE(fs::exists(dir.path / "view.html.tmp"));
  const std::string bad = (dir.path / "missing" / "view.html").string();
  try {
    ff::write_view_html(swinging_scene(), bad);
    ADD_FAILURE() << "no error for " << bad;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
  }
}

TEST(ViewHtml, ThePageHoldsTheScenesNumbersAndEscapesItsTexts) {
  ff::ViewScene s = swinging_scene();
  s.title = "a <b> & c";
  s.variants[1].label = "</script><script>alert(1)</script>";
  s.variants[1].t[1] = 0.0123456789;                // times exactly
  s.variants[1].ends[6 * 2 * 3 + 4] = 1.23456789f;  // positions to 6 significant digits
  s.variants[1].min_clearance = std::nan("");       // no number: null
  // A long run (5000 samples, 1/1024 s apart after 2 s) is thinned to kViewMaxFrames samples, evenly in
  // index (round(k 4999 / 1999)), and the one nearest its worst time.
  ff::ViewVariant& v = s.variants[0];
  const std::size_t per = 12;
  while (v.t.size() < 5000) {
    v.t.push_back(2 + double(v.t.size() - 100) / 1024);
    v.ends.insert(v.ends.end(), v.ends.end() - per, v.ends.end());
    v.rigid_ends.insert(v.rigid_ends.end(), v.rigid_ends.end() - per, v.rigid_ends.end());
    v.tool.insert(v.tool.end(), v.tool.end() - 3, v.tool.end());
  }
  std::size_t dropped = 3000;
  for (int k = 0; k < ff::kViewMaxFrames; ++k)
    if (std::llround(k * 4999.0 / 1999) == long(dropped)) ++dropped, k = -1;
  v.worst_time = v.t[dropped] - 0.0001;  // between samples, nearer the dropped one
  TempDir dir("ff_view_test");
  ff::write_view_html(s, (dir.path / "v.html").string());
  const std::string html = read_text(dir.path / "v.html");
  EXPECT_NE(html.find("\"t\":[0,0.0123456789,0.04,"), std::string::npos);
  EXPECT_NE(html.find(",1.23457,"), std::string::npos);
  EXPECT_NE(html.find("\"min_clearance\":0.12,"), std::string::npos);
  EXPECT_NE(html.find("\"min_clearance\":null,"), std::string::npos);
  EXPECT_NE(html.find("\"worst_b\":[0.6,0.6,0.3]"), std::string::npos);
  EXPECT_NE(html.find("<title>a &lt;b&gt; &amp; c</title>"), std::string::npos);
  EXPECT_NE(html.find("\"\\u003c/script\\u003e\\u003cscript\\u003ealert(1)\\u003c/script\\u003e\""), std::string::npos);
  EXPECT_EQ(html.find("<script>alert(1)"), std::string::npos);
  // variants[0]'s times: 2000 evenly and the dropped one.
  const std::size_t from = html.find("\"t\":[") + 5, to = html.find(']', from);
  const std::string times = html.substr(from, to - from);
  EXPECT_EQ(std::count(times.begin(), times.end(), ',') + 1, ff::kViewMaxFrames + 1);
  EXPECT_NE(times.find("," + std::to_string(v.t[dropped]).substr(0, 6)), std::string::npos);
  EXPECT_NE(html.find("The MIT License"), std::string::npos);  // three.js's licence rides along
}

// ---- In headless Chromium.

struct Shot {
  cv::Mat image;    // BGR, 800 x 600
  std::string dom;  // the page's DOM once drawn
};

// The page at each of `hashes` ("t=1&exaggeration=10") in headless Chromium (tests/chromium.hpp): the
// screenshots (kept as the artefacts `names`) and DOMs; each page must have drawn and reported no error.
std::vector<Shot> open_in_chromium(const fs::path& page, const std::vector<std::string>& hashes,
                                   const std::vector<std::string>& names, const TempDir& dir) {
  std::vector<ff::test::BrowserPage> pages;
  for (std::size_t i = 0; i < hashes.size(); ++i) pages.push_back({"file://" + page.string() + "#" + hashes[i], names[i]});
  const std::vector<std::string> doms = ff::test::load_in_chromium(pages, dir.path, 800, 600);
  std::vector<Shot> shots(hashes.size());
  for (std::size_t i = 0; i < hashes.size(); ++i) {
    Shot& shot = shots[i];
    shot.dom = doms[i];
    if (shot.dom.empty()) continue;
    shot.image = cv::imread((dir.path / names[i]).string(), cv::IMREAD_COLOR);
    if (shot.image.empty()) {
      ADD_FAILURE() << "no screenshot of #" << hashes[i];
      continue;
    }
    // Drawn at the requested time, and no JavaScript error (the page marks both on <html>; the banner says it).
    const std::string html_tag = shot.dom.substr(0, shot.dom.find('>', shot.dom.find("<html")));
    const std::size_t banner = shot.dom.find("<div id=\"error\"");
    EXPECT_NE(html_tag.find("data-view-ready="), std::string::npos) << "#" << hashes[i] << ": the page never drew a frame";
    EXPECT_EQ(html_tag.find("data-view-error="), std::string::npos)
        << "#" << hashes[i] << ": the page reported an error: " << shot.dom.substr(banner, shot.dom.find("</div>", banner) - banner);
  }
  return shots;
}

// The 3-D view above the control panel (its bottom 100 px show the time and the slider).
cv::Mat view_region(const cv::Mat& image) { return image(cv::Rect(0, 30, image.cols, image.rows - 130)); }

// The share of the view's pixels differing by more than 24 in some channel between two shots.
double changed_share(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat diff;
  cv::absdiff(view_region(a), view_region(b), diff);
  int changed = 0;
  for (int y = 0; y < diff.rows; ++y)
    for (int x = 0; x < diff.cols; ++x) {
      const cv::Vec3b d = diff.at<cv::Vec3b>(y, x);
      changed += std::max({d[0], d[1], d[2]}) > 24;
    }
  return double(changed) / double(diff.total());
}

// The solid arm's pixels: strongly blue (the ghosts are pale).
cv::Mat arm_pixels(const cv::Mat& image) {
  const cv::Mat view = view_region(image);
  cv::Mat mask(view.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < view.rows; ++y)
    for (int x = 0; x < view.cols; ++x) {
      const cv::Vec3b p = view.at<cv::Vec3b>(y, x);  // BGR
      mask.at<uchar>(y, x) = p[0] > p[2] + 60 && p[0] > p[1] + 30 ? 255 : 0;
    }
  return mask;
}

TEST(ViewHtml, TheArmsPixelsMoveBetweenTwoTimesInHeadlessChromium) {
  TempDir dir("ff_view_test");
  const fs::path page = dir.path / "view.html";
  ff::write_view_html(swinging_scene(), page.string());
  fs::copy_file(page, ff::test::artefact("view_swing.html"), fs::copy_options::overwrite_existing);
  const std::vector<Shot> shots = open_in_chromium(page, {"t=0", "t=2"}, {"view_t0.png", "view_t2.png"}, dir);
  if (shots.size() != 2 || shots[0].image.empty() || shots[1].image.empty()) return;
  const Shot &a = shots[0], &b = shots[1];
  ASSERT_EQ(a.image.size(), cv::Size(800, 600));

  // Not blank: the grid, the box, the floor and the arm's shading give many colours, most of the view
  // differs from the background.
  const cv::Mat view = view_region(a.image);
  std::vector<int> colours;
  int background = 0;
  for (int y = 0; y < view.rows; ++y)
    for (int x = 0; x < view.cols; ++x) {
      const cv::Vec3b p = view.at<cv::Vec3b>(y, x);
      colours.push_back(p[0] << 16 | p[1] << 8 | p[2]);
      background += p == cv::Vec3b(0xf7, 0xf5, 0xf4);
    }
  std::sort(colours.begin(), colours.end());
  EXPECT_GT(std::unique(colours.begin(), colours.end()) - colours.begin(), 200);
  EXPECT_LT(double(background) / double(view.total()), 0.9);

  // The arm is seen at both times, and swung 90 degrees: its pixels barely overlap.
  const cv::Mat arm0 = arm_pixels(a.image), arm2 = arm_pixels(b.image);
  const int n0 = cv::countNonZero(arm0), n2 = cv::countNonZero(arm2);
  cv::Mat both;
  cv::bitwise_and(arm0, arm2, both);
  std::cout << "arm pixels: " << n0 << " at t = 0, " << n2 << " at t = 2, " << cv::countNonZero(both)
            << " in common; view changed: " << 100 * changed_share(a.image, b.image) << " %\n";
  EXPECT_GT(n0, 1000);
  EXPECT_GT(n2, 1000);
  EXPECT_LT(cv::countNonZero(both), 0.3 * std::min(n0, n2)) << n0 << " and " << n2 << " arm pixels";
  EXPECT_GT(changed_share(a.image, b.image), 0.01);
}

TEST(ViewHtml, TheExaggerationBendsTheDeflectedCapsuleInHeadlessChromium) {
  TempDir dir("ff_view_test");
  const fs::path page = dir.path / "view.html";
  ff::write_view_html(swinging_scene(), page.string());
  const std::vector<Shot> shots = open_in_chromium(page, {"t=0.5&exaggeration=1", "t=0.5&exaggeration=10"},
                                                   {"view_t0.5_x1.png", "view_t0.5_x10.png"}, dir);
  if (shots.size() != 2 || shots[0].image.empty() || shots[1].image.empty()) return;
  const Shot &a = shots[0], &b = shots[1];
  // The forearm's 3 cm droop, times 10, moves its pixels.
  std::cout << "view changed: " << 100 * changed_share(a.image, b.image) << " %\n";
  EXPECT_GT(changed_share(a.image, b.image), 0.005);
  EXPECT_NE(b.dom.find("<span id=\"exaggeration-value\">10.0</span>"), std::string::npos);
  EXPECT_NE(b.dom.find("t = 0.500 s | variant 0: nominal | min clearance 0.1200 m at t = 1.000 s: forearm to box | "
                       "1 ghost, lowest 0.08000 m: variant 1: ghost</div>"),
            std::string::npos);
}

// A large world (a tank's wall 20 m across, a 40 m box far off, a waste plane) around the same 1.1 m arm:
// the camera frames the arm's swept volume, not the world, so the arm is as large as without it; a scale
// bar (a 1-2-5 length with its unit) and the grid's step and the axes are said at the top right.
TEST(ViewHtml, TheCameraFramesTheArmNotALargeWorldAndAScaleBarSaysItsLength) {
  TempDir dir("ff_view_test");
  ff::ViewScene s = swinging_scene();
  ff::ViewShape tank, far, waste;
  tank.name = "tank", tank.type = "bore", tank.radius = 10, tank.length = 15;
  far.name = "far", far.type = "box", far.size << 40, 40, 40;
  far.pose.topRightCorner<3, 1>() << 60, -60, 0;
  waste.name = "waste", waste.type = "plane";
  waste.pose(2, 3) = -8;
  s.shapes.insert(s.shapes.end(), {tank, far, waste});
  const fs::path page = dir.path / "view.html";
  ff::write_view_html(s, page.string());
  fs::copy_file(page, ff::test::artefact("view_large_world.html"), fs::copy_options::overwrite_existing);
  const std::vector<Shot> shots = open_in_chromium(page, {"t=0"}, {"view_large_world.png"}, dir);
  if (shots.size() != 1 || shots[0].image.empty()) return;
  const Shot& a = shots[0];
  const int arm = cv::countNonZero(arm_pixels(a.image));
  std::cout << "arm pixels in a large world: " << arm << "\n";
  EXPECT_GT(arm, 1000);  // the world framed instead: about 20
  // Framed: the arms' swept box, the 0.05 m radius around it: x from 1.1 cos(pi/2 + 0.15) (the ghost) to 1.1,
  // y from 0 to 1.1, z from 0.27 (the droop) to 0.3; its diagonal sqrt(1.364^2 + 1.2^2 + 0.13^2) = 1.822 m.
  const std::size_t frame = a.dom.find("data-view-frame=\"");
  ASSERT_NE(frame, std::string::npos);
  EXPECT_NEAR(std::stod(a.dom.substr(frame + 17)), 1.822, 0.002);
  // The scale bar: a 1-2-5 length with its unit (20 cm at 309 px/m, the orbit centre 2.66 m away).
  EXPECT_TRUE(std::regex_search(a.dom, std::regex(R"(<span id="scale-bar" style="width: \d+px;"></span> <span id="scale-text">[125]0? (mm|cm|m)</span>)")))
      << a.dom.substr(a.dom.find("<div id=\"scale\">"), 300);
  EXPECT_NE(a.dom.find("<div id=\"legend\">grid 50 cm; axes at the base: x red, y green, z blue, 50 cm long</div>"),
            std::string::npos);
}

}  // namespace
