// Tests of the 3-D arm view: the pinhole projection against its formula, a 2R arm's frames at two
// poses differing only where the forearm moved, the video's frame count and atomic write, the
// still, a non-finite state drawn as a warning, and an ArmModel's run (a swung flexible link) end to end.
#include "plotting/animate3d.hpp"
#include "plotting/animate3d_arm.hpp"

#include "arm/arm_simulate.hpp"
#include "arm/arm_yaml.hpp"
#include "common/yaml_reader.hpp"
#include "multibody/algorithms.hpp"
#include "tests/plotting/test_support.hpp"

#include <gtest/gtest.h>
// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#pragma GCC diagnostic pop

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace {

using ff::Vec3;
using ff::test::TempDir;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ff::Camera fixed_camera(double az, double el, double distance) {
  ff::Camera c;
  c.azimuth = az, c.elevation = el, c.distance = distance;
  c.target = Vec3(0.2, -0.1, 0.3);
  c.width = 800, c.height = 600;
  return c;
}

TEST(Animate3d, TheProjectionIsThePinholeFormula) {
  const ff::Camera c = fixed_camera(0.0, 0.0, 2.0);  // from +x, level: base y is to the right, z up
  const ff::CameraView v = ff::camera_view(c, Vec3::UnitZ());
  const double focal = 300.0 / std::tan(20 * ff::kDegree);
  EXPECT_NEAR(v.focal, focal, 1e-9);
  EXPECT_NEAR((v.eye - Vec3(2.2, -0.1, 0.3)).norm(), 0.0, 1e-12);
  // On the camera axis: the image centre, at any depth.
  for (double s : {-1.0, 0.0, 0.7, 5.0}) {
    const ff::Projected p = ff::project(v, c.target + s * v.forward);
    EXPECT_NEAR(p.x, 399.5, 1e-9);
    EXPECT_NEAR(p.y, 299.5, 1e-9);
    EXPECT_NEAR(p.depth, 2.0 + s, 1e-12);
  }
  // 1 m to the right (base +y seen from +x): focal / depth px right of the centre, on its row; up: above.
  const ff::Projected r = ff::project(v, c.target + Vec3(0, 1, 0));
  EXPECT_NEAR(r.x - 399.5, focal / 2.0, 1e-9);
  EXPECT_NEAR(r.y, 299.5, 1e-9);
  const ff::Projected u = ff::project(v, c.target + Vec3(0, 0, 0.5));
  EXPECT_NEAR(299.5 - u.y, focal * 0.5 / 2.0, 1e-9);
  EXPECT_NEAR(u.x, 399.5, 1e-9);
  // Perspective: the same 1 m offset s farther away shrinks by 2 / (2 + s).
  for (double s : {0.5, 1.0, 3.0}) {
    const ff::Projected far = ff::project(v, c.target - Vec3(s, 0, 0) + Vec3(0, 1, 0));
    EXPECT_NEAR((far.x - 399.5) / (r.x - 399.5), 2.0 / (2.0 + s), 1e-12) << s;
  }
  // Any azimuth and elevation: the eye at the distance, the target at the centre, the frame orthonormal,
  // "right" level (perpendicular to up), and a point to the right of the target drawn right of centre.
  for (double az : {-2.0, -0.9, 0.4, 2.5})
    for (double el : {-1.2, 0.0, 0.5, 1.4}) {
      const ff::CameraView w = ff::camera_view(fixed_camera(az, el, 3.0), Vec3::UnitZ());
      EXPECT_NEAR((w.eye - c.target).norm(), 3.0, 1e-12);
      const ff::Projected t = ff::project(w, c.target);
      EXPECT_NEAR(t.x, 399.5, 1e-9);
      EXPECT_NEAR(t.y, 299.5, 1e-9);
      EXPECT_NEAR(w.right.dot(Vec3::UnitZ()), 0.0, 1e-12);
      EXPECT_NEAR(w.right.dot(w.forward), 0.0, 1e-12);
      EXPECT_NEAR(w.up.dot(w.forward), 0.0, 1e-12);
      EXPECT_GT(w.up.dot(Vec3::UnitZ()), 0.0);  // the image is not upside down
      EXPECT_GT(ff::project(w, c.target + 0.3 * w.right).x, 399.5 + 1.0);
    }
  // Straight from above (elevation 90 degrees): the azimuth's direction points down the image, right is level.
  const ff::CameraView top = ff::camera_view(fixed_camera(0.0, 90 * ff::kDegree, 2.0), Vec3::UnitZ());
  EXPECT_NEAR((top.right - Vec3::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((top.forward + Vec3::UnitZ()).norm(), 0.0, 1e-12);
  EXPECT_GT(ff::project(top, c.target + Vec3(0.5, 0, 0)).y, 299.5 + 1.0);
  EXPECT_NEAR(ff::project(top, c.target + Vec3(0, 0.5, 0)).x - 399.5, top.focal * 0.5 / 2.0, 1e-9);
  // Up follows gravity.
  ff::TreeSpec spec;
  spec.bodies.push_back({});
  spec.gravity = Vec3(0, -9.81, 0);
  EXPECT_NEAR((ff::up_direction(ff::make_tree(spec)) - Vec3::UnitY()).norm(), 0.0, 1e-15);
  // Bad cameras are rejected.
  EXPECT_THROW(ff::camera_view(fixed_camera(0, 0, 0), Vec3::UnitZ()), std::invalid_argument);
  EXPECT_THROW(ff::camera_view(fixed_camera(0, 1.6, 2), Vec3::UnitZ()), std::invalid_argument);
  ff::Camera wide = fixed_camera(0, 0, 2);
  wide.fov = 3.2;
  EXPECT_THROW(ff::camera_view(wide, Vec3::UnitZ()), std::invalid_argument);
}

// A 2R arm: an upper arm 0.6 m about z at the base, a forearm about z at its end, gravity -z (it swings in
// the horizontal plane), the tool 0.5 m along the forearm.
ff::Tree two_r() {
  ff::TreeSpec spec;
  ff::BodySpec upper;
  upper.name = "upper", upper.mass = 1.0, upper.com = Vec3(0.3, 0, 0);
  upper.inertia = Eigen::Vector3d(0.001, 0.03, 0.03).asDiagonal();
  ff::BodySpec fore;
  fore.name = "fore", fore.parent = 0, fore.position = Vec3(0.6, 0, 0), fore.mass = 0.5, fore.com = Vec3(0.25, 0, 0);
  fore.inertia = Eigen::Vector3d(0.001, 0.01, 0.01).asDiagonal();
  spec.bodies = {upper, fore};
  return ff::make_tree(spec);
}

ff::ArmShape two_r_shape() {
  ff::ArmShape s;
  s.tool_body = 1, s.tool_point = Vec3(0.5, 0, 0);
  return s;
}

// Distance from p to the segment ab, px.
double to_segment(cv::Point2d p, cv::Point2d a, cv::Point2d b) {
  const cv::Point2d d = b - a;
  const double t = std::clamp((p - a).dot(d) / std::max(d.dot(d), 1e-12), 0.0, 1.0);
  const cv::Point2d c = a + d * t;
  return std::hypot(p.x - c.x, p.y - c.y);
}

TEST(Animate3d, TwoPosesOfA2RArmDifferOnlyWhereTheForearmMoved) {
  const ff::Tree tree = two_r();
  const ff::ArmShape shape = two_r_shape();
  Eigen::MatrixXd qs(2, 2);
  qs << 0.3, 0.3, 0.2, 1.4;  // the forearm turns, the upper arm stays
  ff::Camera cam;
  cam.width = 640, cam.height = 480;
  ff::ArmDrawStyle style;
  style.shadows = false;  // (a shadow moves too, elsewhere on the ground)
  ff::fit_arm_view(tree, shape, qs, cam, style);
  ASSERT_GT(cam.distance, 0.0);
  ASSERT_TRUE(cam.target.allFinite());
  const cv::Mat a = ff::render_arm_frame(tree, shape, qs.col(0), cam, style);
  const cv::Mat b = ff::render_arm_frame(tree, shape, qs.col(1), cam, style);
  ASSERT_EQ(a.rows, 480);
  ASSERT_EQ(a.cols, 640);
  ASSERT_EQ(a.type(), CV_8UC3);
  // The same inputs give the same pixels.
  EXPECT_EQ(cv::norm(a, ff::render_arm_frame(tree, shape, qs.col(0), cam, style), cv::NORM_INF), 0.0);

  const ff::CameraView v = ff::camera_view(cam, ff::up_direction(tree));
  const auto px = [&](const Vec3& p) {
    const ff::Projected q = ff::project(v, p);
    return cv::Point2d(q.x, q.y);
  };
  const auto forearm = [&](int k) {
    const Vec3 elbow = ff::calc_point_position(tree, qs.col(k), 1, Vec3::Zero());
    const Vec3 tool = ff::calc_point_position(tree, qs.col(k), 1, Vec3(0.5, 0, 0));
    return std::pair{px(elbow), px(tool)};
  };
  const auto [ea, ta] = forearm(0);
  const auto [eb, tb] = forearm(1);
  // Within a margin of either forearm (its sphere, ring and tool dot are at most ~3 link radii across).
  const double margin = 4.0 * v.focal * style.sphere_radius / cam.distance + 6;
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  int changed = 0, stray = 0;
  for (int y = 0; y < diff.rows; ++y)
    for (int x = 0; x < diff.cols; ++x) {
      const cv::Vec3b d = diff.at<cv::Vec3b>(y, x);
      if (d[0] == 0 && d[1] == 0 && d[2] == 0) continue;
      ++changed;
      const cv::Point2d p(x, y);
      if (std::min(to_segment(p, ea, ta), to_segment(p, eb, tb)) > margin) ++stray;
    }
  EXPECT_GT(changed, 500);
  EXPECT_EQ(stray, 0) << "pixels changed away from both forearms";
  // Mid-forearm of the second pose is drawn there and not in the first; the upper arm's middle is the same.
  const cv::Point2d mid_b = (eb + tb) * 0.5;
  EXPECT_GT(cv::norm(a.at<cv::Vec3b>(int(mid_b.y), int(mid_b.x)), b.at<cv::Vec3b>(int(mid_b.y), int(mid_b.x))), 60.0);
  const cv::Point2d mid_upper = px(ff::calc_point_position(tree, qs.col(0), 0, Vec3(0.15, 0, 0)));
  EXPECT_EQ(a.at<cv::Vec3b>(int(mid_upper.y), int(mid_upper.x)), b.at<cv::Vec3b>(int(mid_upper.y), int(mid_upper.x)));
  EXPECT_NE(a.at<cv::Vec3b>(int(mid_upper.y), int(mid_upper.x)), cv::Vec3b(255, 255, 255));  // the link is there
}

TEST(Animate3d, ANonFiniteStateIsAWarningNotACrash) {
  const ff::Tree tree = two_r();
  ff::Camera cam;
  cam.width = 480, cam.height = 360;
  const cv::Mat img = ff::render_arm_frame(tree, two_r_shape(), Eigen::Vector2d(0.1, kNaN), cam, {}, 1.5);
  ASSERT_EQ(img.rows, 360);
  // The warning's vermillion (213, 94, 0) text across the middle.
  int red = 0;
  for (int y = 150; y < 210; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b c = img.at<cv::Vec3b>(y, x);
      red += c[2] > 150 && c[1] < 130 && c[0] < 80;
    }
  EXPECT_GT(red, 100);
  EXPECT_THROW(ff::render_arm_frame(tree, two_r_shape(), Eigen::Vector3d::Zero(), cam, {}), std::invalid_argument);
  ff::ArmShape bad = two_r_shape();
  bad.tool_body = 7;
  EXPECT_THROW(ff::render_arm_frame(tree, bad, Eigen::Vector2d::Zero(), cam, {}), std::invalid_argument);
}

TEST(Animate3d, FramesAreTheLastSampleAtOrBeforeEachFrameTime) {
  std::vector<double> t;
  for (int i = 0; i <= 100; ++i) t.push_back(0.01 * i);
  const std::vector<int> s = ff::arm_animation_samples(t, 20, 1);
  ASSERT_EQ(s.size(), 21u);
  for (size_t k = 0; k < s.size(); ++k) EXPECT_EQ(s[k], int(5 * k));
  EXPECT_EQ(ff::arm_animation_samples(t, 20, 2).size(), 11u);
  const std::vector<int> s30 = ff::arm_animation_samples(t, 30, 1);
  ASSERT_EQ(s30.size(), 31u);
  EXPECT_EQ(s30[29], 96);   // 29/30 s = 0.9667 s: the sample at 0.96 s
  EXPECT_EQ(s30[30], 100);
  EXPECT_EQ(ff::arm_animation_samples(std::vector<double>{3.0}, 30, 1), std::vector<int>{0});
  EXPECT_THROW(ff::arm_animation_samples(std::vector<double>{}, 30, 1), std::invalid_argument);
  EXPECT_THROW(ff::arm_animation_samples(std::vector<double>{0, 0.1, 0.1}, 30, 1), std::invalid_argument);
  EXPECT_THROW(ff::arm_animation_samples(t, 0, 1), std::invalid_argument);
  EXPECT_THROW(ff::arm_animation_samples(t, 30, -1), std::invalid_argument);
}

int count_frames(const std::string& path) {
  cv::VideoCapture in(path, cv::CAP_FFMPEG);
  if (!in.isOpened()) return -1;
  int n = 0;
  for (cv::Mat m; in.read(m);) ++n;
  return n;
}

TEST(Animate3d, TheVideoHasOneFramePerFrameTimeAndIsWrittenAtomically) {
  TempDir dir;
  const ff::Tree tree = two_r();
  std::vector<double> t;
  Eigen::MatrixXd qs(2, 101);
  for (int i = 0; i <= 100; ++i) {
    t.push_back(0.01 * i);
    qs.col(i) << 0.8 * t.back(), 1.5 * t.back();
  }
  qs(1, 50) = kNaN;  // frame 10 (t = 0.5 s) shows the warning
  const std::string path = (dir.path / "arm.avi").string(), png = (dir.path / "still.png").string();
  {
    std::ofstream old(path);
    old << "an older video";
  }
  ff::ArmAnimationOptions o;
  o.fps = 20;
  o.camera.width = 320, o.camera.height = 240;
  o.style.title = "2R arm";
  o.still_path = png, o.still_time = 0.73;
  const ff::ArmAnimationSummary sum = ff::write_arm_animation(tree, two_r_shape(), t, qs, path, o);
  EXPECT_EQ(sum.frames, 21);
  EXPECT_EQ(sum.nonfinite_frames, 1);
  EXPECT_DOUBLE_EQ(sum.still_time, 0.73);
  EXPECT_EQ(count_frames(path), 21);
  const cv::Mat still = cv::imread(png);
  EXPECT_EQ(still.cols, 320);
  EXPECT_EQ(still.rows, 240);
  // Only the two files: the temporaries were renamed.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 2);
  // The still is write_arm_still's frame, and the last sample at or before its time.
  const std::string png2 = (dir.path / "still2.png").string();
  EXPECT_DOUBLE_EQ(ff::write_arm_still(tree, two_r_shape(), t, qs, 0.735, png2, o), 0.73);
  EXPECT_EQ(cv::norm(still, cv::imread(png2), cv::NORM_INF), 0.0);
  // Wrong sizes are rejected before any file is touched; an unwritable place names the path.
  EXPECT_THROW(ff::write_arm_animation(tree, two_r_shape(), t, qs.leftCols(100), path, o), std::invalid_argument);
  const std::string nowhere = (dir.path / "no_such_dir" / "arm.avi").string();
  try {
    ff::write_arm_animation(tree, two_r_shape(), t, qs, nowhere, o);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(nowhere), std::string::npos) << e.what();
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path), {}), 3);
}

// A column turning about z, an upper arm about y, and a flexible aluminium forearm about y (24 elastic
// dofs), swung by its controllers: the run's kept q drawn through the ArmModel adapter.
const char* kFlexibleArm = R"(description: "3-DOF arm, flexible forearm"
gravity: [0, 0, -9.81]
bodies:
  - {name: column, parent: base, mass: 4.0, com: [0, 0, 0.2], inertia: {ixx: 0.02, iyy: 0.02, izz: 0.01}, joint: {axis: [0, 0, 1], armature: 0.05}}
  - {name: upper, parent: column, mass: 1.5, com: [0.2, 0, 0], inertia: {ixx: 0.001, iyy: 0.02, izz: 0.02}, joint: {axis: [0, 1, 0], position: [0, 0, 0.4], armature: 0.05}}
  - name: fore
    parent: upper
    joint: {axis: [0, 1, 0], position: [0.4, 0, 0], armature: 0.05}
    flexible:
      length: 0.6
      segments: 9
      section: {E: 70e9, G: 26e9, density: 2700, area: 1.2e-4, I_y: 1.0e-10, I_z: 1.0e-8, J: 4e-10}
tool: {body: fore}
joints:
  column: {controller: {kp: 300, kd: 30, gravity_compensation: 1}}
  upper: {controller: {kp: 300, kd: 30, gravity_compensation: 1}}
  fore: {controller: {kp: 200, kd: 20, gravity_compensation: 1}}
trajectory:
  waypoints:
    - {time: 0.6, joints: {column: 1.0, upper: -0.5, fore: 0.6}}
simulation: {duration: 0.8}
)";

TEST(Animate3d, AnArmModelsRunIsDrawnWithItsFlexibleLinkExaggerated) {
  TempDir dir;
  const ff::ArmModel arm = ff::parse_arm(ff::load_yaml_text(kFlexibleArm, "arm.yaml"), "arm.yaml");
  const ff::ArmShape shape = ff::arm_shape(arm);
  ASSERT_EQ(shape.flexible_links.size(), 1u);
  EXPECT_EQ(shape.flexible_links[0].elastic_dofs, arm.links[0].elastic_dofs);
  EXPECT_EQ(shape.tool_body, arm.tool_body);
  const ff::ArmRun run = ff::simulate_arms(std::span<const ff::ArmModel>(&arm, 1), {.keep_q = true});
  ASSERT_EQ(run.status[0], ff::LaneStatus::kOk);
  const std::vector<double>& t = run.traces[0].t();
  // The tool point as drawn (exaggeration 1) is the trace's tool.
  const size_t last = t.size() - 1;
  const Vec3 tool = ff::arm_tool_position(arm.tree, shape, run.q[0].col(Eigen::Index(last)), 1.0);
  EXPECT_NEAR(tool.x(), run.traces[0].column("tool.x")[last], 1e-12);
  EXPECT_NEAR(tool.z(), run.traces[0].column("tool.z")[last], 1e-12);

  ff::ArmAnimationOptions o;
  o.fps = 25;
  o.camera.width = 480, o.camera.height = 360;
  o.style.exaggeration = 30;
  o.still_path = (dir.path / "still.png").string(), o.still_time = 0.4;
  const std::string path = (dir.path / "arm.avi").string();
  const ff::ArmAnimationSummary sum = ff::write_arm_animation(arm, t, run.q[0], path, o);
  EXPECT_EQ(sum.frames, 21);  // 0.8 s at 25 fps
  EXPECT_EQ(sum.nonfinite_frames, 0);
  EXPECT_EQ(count_frames(path), 21);
  // The exaggeration bends only the flexible link: the frames at 1x and 30x differ, and not everywhere.
  ff::Camera cam = o.camera;
  ff::ArmDrawStyle one = o.style, many = o.style;
  one.exaggeration = 1;
  ff::fit_arm_view(arm.tree, shape, run.q[0], cam, many);
  one.link_radius = many.link_radius, one.sphere_radius = many.sphere_radius, one.ground = many.ground;
  one.grid_centre = many.grid_centre, one.grid_half_size = many.grid_half_size, one.grid_step = many.grid_step;
  const Eigen::VectorXd q = run.q[0].col(Eigen::Index(std::lround(0.4 / arm.control_period)));
  const cv::Mat a = ff::render_arm_frame(arm, q, cam, one), b = ff::render_arm_frame(arm, q, cam, many);
  cv::Mat diff, grey;
  cv::absdiff(a, b, diff);
  cv::cvtColor(diff, grey, cv::COLOR_BGR2GRAY);
  const int changed = cv::countNonZero(grey);
  EXPECT_GT(changed, 200);
  EXPECT_LT(changed, a.rows * a.cols / 4);
  if (const char* out = std::getenv("FLEXFARM_ANIMATE3D_SAMPLE")) {  // a look at it: the still at 0.45 s
    ff::ArmAnimationOptions big = o;
    big.camera.width = 1280, big.camera.height = 960;
    big.still_path.clear();
    EXPECT_NEAR(ff::write_arm_still(arm, t, run.q[0], 0.45, out, big), 0.45, 1e-12);
  }
}


TEST(Animate3d, EveryToolOfATwoArmedMachineGetsItsDotAndPath) {
  // configs/sers.yaml's two tools: the first as tool_body/tool_point, the second in more_tools; each as
  // drawn is where the trace puts it; a still of both is written.
  TempDir dir;
  const std::string path = std::string(FLEXFARM_SOURCE_DIR) + "/configs/sers.yaml";
  YAML::Node doc = ff::load_yaml_file(path);
  doc["simulation"]["duration"] = 1.0;
  const ff::ArmModel arm = ff::parse_arm(doc, path);
  const ff::ArmShape shape = ff::arm_shape(arm);
  ASSERT_EQ(shape.more_tools.size(), 1u);
  EXPECT_EQ(shape.more_tools[0].first, arm.tools[1].body);
  const ff::ArmRun run = ff::simulate_arms(std::span<const ff::ArmModel>(&arm, 1), {.keep_q = true});
  ASSERT_EQ(run.status[0], ff::LaneStatus::kOk);
  const size_t last = run.traces[0].t().size() - 1;
  const Eigen::VectorXd q = run.q[0].col(Eigen::Index(last));
  const Vec3 left = ff::arm_tool_position(arm.tree, shape, q, 1.0);
  const Vec3 right = ff::arm_more_tool_position(arm.tree, shape, 0, q, 1.0);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(left[k], run.traces[0].column(std::string("left.") + "xyz"[k])[last], 1e-12);
    EXPECT_NEAR(right[k], run.traces[0].column(std::string("right.") + "xyz"[k])[last], 1e-12);
  }
  EXPECT_TRUE(std::isnan(ff::arm_more_tool_position(arm.tree, shape, 1, q, 1.0).x()));  // no third tool
  ff::ArmAnimationOptions o;
  o.camera.width = 480, o.camera.height = 360;
  const std::string still = (dir.path / "still.png").string();
  EXPECT_NEAR(ff::write_arm_still(arm, run.traces[0].t(), run.q[0], 0.9, still, o), 0.9, 1e-9);
  EXPECT_TRUE(std::filesystem::exists(still));
}

}  // namespace
