// A 3-D view of any arm: frames of a kinematic tree (multibody/tree.hpp) at a joint state q, seen by a
// perspective camera, and a video of a joint trajectory (arm/arm_simulate.hpp's ArmRun::q with
// ArmRunOptions::keep_q). plotting/animate3d_arm.hpp takes the shape from an ArmModel.
//
// What is drawn (painter's algorithm: every piece sorted by its distance from the camera, far first,
// far pieces paler):
//   ground   a grid on the plane perpendicular to gravity through the lowest drawn point (over the
//            whole video), the links' shadows straight down on it, the base as a dark plate with a
//            post down to the ground;
//   links    each rigid body as a capsule from its joint origin to each child's joint origin (a leaf:
//            to its centre of mass and to the tool point), so the chain reads joint to joint;
//   masses   each rigid body with mass as a sphere at its centre of mass, its volume in proportion to
//            the mass (the heaviest body's radius is ArmDrawStyle::sphere_radius);
//   flexible each flexible link as a thick polyline through its segments' origins to its tip, its
//            elastic dofs multiplied by ArmDrawStyle::exaggeration before the forward kinematics;
//   joints   each moving joint that is not elastic as a small ring;
//   tool     the tool point's path as a polyline fading with age, and the tool point as a dot;
//   text     the title, the time stamp, the grid step and the exaggeration.
// Image coordinates: x right, y down, pixel centres at integers, the view axis through the image
// centre ((width - 1) / 2, (height - 1) / 2).
//
// OpenCV's core header is included for cv::Mat (the other plotting headers keep OpenCV out): a
// frame comes back as an 8-bit BGR image, ready for cv::imwrite or cv::VideoWriter.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

// OpenCV 4.6 headers mix enum types, which C++20 deprecates; keep that noise out of our build.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/core.hpp>
#pragma GCC diagnostic pop

#include "multibody/spatial.hpp"
#include "multibody/tree.hpp"

namespace ff {

// A flexible link of the tree: the chain of segment bodies from root_body to tip_body (each the
// parent of the next, through the massless bodies of the cell joints).
struct FlexibleLinkShape {
  int root_body = -1, tip_body = -1;
  Vec3 tip_point = Vec3::Zero();   // in the tip body's frame, m
  std::vector<int> elastic_dofs;   // the cell joints' dofs (scaled by ArmDrawStyle::exaggeration)
};

// What the tree alone does not say: which bodies are flexible links, and the tool point.
struct ArmShape {
  std::vector<FlexibleLinkShape> flexible_links;
  int tool_body = -1;              // -1 = no tool point (no path, no dot)
  Vec3 tool_point = Vec3::Zero();  // in the tool body's frame, m
  // Further tool points (a two-armed tree's second tool): body and point each, a dot and a path each.
  std::vector<std::pair<int, Vec3>> more_tools;
};

inline constexpr double kDegree = 3.14159265358979323846 / 180.0;

// Where the camera is. "Up" is against gravity (+z for a tree without gravity); the azimuth is measured
// about up from the base x axis laid on the ground (base y when x is vertical) towards base y.
struct Camera {
  double azimuth = -55 * kDegree;   // rad; the default looks from +x, -y (front right for a z-up base)
  double elevation = 25 * kDegree;  // rad above the ground plane, within [-90, 90] degrees (90: from above,
                                    // the azimuth's direction pointing down the image)
  double distance = 0;              // m from the target; 0 = fit: the arm's bounding sphere fills the view
  double fov = 40 * kDegree;        // vertical field of view, rad, in (0, 180) degrees
  Vec3 target = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());  // base frame; NaN = the
                                                                           // arm's bounding-box centre
  int width = 960, height = 720;    // px, at least 240 x 240
};

// A camera with everything resolved (camera_view): the eye and its orthonormal frame.
struct CameraView {
  Vec3 eye = Vec3::Zero();
  Vec3 forward = Vec3::UnitX(), right = -Vec3::UnitY(), up = Vec3::UnitZ();  // base frame, unit
  double focal = 1;                 // px: (height / 2) / tan(fov / 2)
  double cx = 0, cy = 0;            // the image centre, px
  int width = 0, height = 0;
};

// A point on the image: x, y in px; depth the distance along the view axis, m (<= 0: behind the eye).
struct Projected {
  double x = 0, y = 0, depth = 0;
};

// The direction drawn as up: -gravity normalised, +z for zero gravity.
Vec3 up_direction(const Tree& tree);
// The camera resolved: eye = target + distance (cos el (cos az e1 + sin az e2) + sin el up), looking at
// the target. Throws std::invalid_argument for a distance <= 0, a non-finite target or angle, an
// elevation outside [-90, 90] degrees, a field of view outside (0, 180) degrees or a too small image.
// The image's right is always level: right = -sin(az) e1 + cos(az) e2.
CameraView camera_view(const Camera& camera, const Vec3& up);
// Pinhole projection: depth = (p - eye).forward, x = cx + focal (p - eye).right / depth,
// y = cy - focal (p - eye).up / depth. A point 1 m off the axis at depth d lies focal / d px out.
Projected project(const CameraView& view, const Vec3& p);

// How the arm is drawn. Lengths in m; 0 (or NaN) = fitted to the arm by fit_arm_view.
struct ArmDrawStyle {
  std::string title;                // ASCII after canvas's spelling of common signs
  double exaggeration = 1;          // elastic dofs x this before the kinematics (1 = the true shape)
  double link_radius = 0;           // capsules; 0 = 1/70 of the bounding sphere's radius
  double sphere_radius = 0;         // the heaviest body's sphere; 0 = 2.6 link radii
  double ground = std::numeric_limits<double>::quiet_NaN();  // the ground's height along up; NaN = the
                                                             // lowest drawn point
  double grid_step = 0;             // grid spacing; 0 = a 1-2-5 step, about a fifth of the arm's size
  double grid_half_size = 0;        // the grid's half width around the arm's centre; 0 = 1.4 x its size
  Vec3 grid_centre = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());  // NaN = below the
                                                                                // bounding-box centre
  bool shadows = true;              // the links' shadows on the ground
  double depth_fade = 0.35;         // the farthest pieces mixed this much with white (depth cue)
};

// Fills every automatic field of `camera` and `style` from the arm at the joint states `qs` (nv x
// frames, one column per frame; non-finite columns ignored; with none finite, the arm at q = 0), so
// one fit serves a whole video and the view never re-zooms. Explicit fields are kept.
void fit_arm_view(const Tree& tree, const ArmShape& shape, const Eigen::Ref<const Eigen::MatrixXd>& qs,
                  Camera& camera, ArmDrawStyle& style);

// The tool point at q (the elastic dofs x exaggeration first), base frame, m; NaN when q is not
// finite or the shape has no tool.
Vec3 arm_tool_position(const Tree& tree, const ArmShape& shape, const Eigen::Ref<const Eigen::VectorXd>& q,
                       double exaggeration);
// The same for shape.more_tools[k].
Vec3 arm_more_tool_position(const Tree& tree, const ArmShape& shape, std::size_t k,
                            const Eigen::Ref<const Eigen::VectorXd>& q, double exaggeration);

// One frame of the arm at q (nv values) as a BGR image (camera.height x camera.width, CV_8UC3). Automatic
// camera and style fields are fitted to this q alone (fit_arm_view). `t`: the time stamp, s (NaN =
// none). `tool_path`: the tool's earlier positions, oldest first, drawn fading from the newest
// (non-finite points break it); `more_paths`: those of ArmShape::more_tools, in their order. A non-finite q is not drawn: the ground, the text and a red warning
// "non-finite joint state: arm not drawn" are. Throws std::invalid_argument for q of the wrong size,
// a bad camera (camera_view) or a bad shape (a body index out of range, a flexible link whose
// tip is not below its root).
cv::Mat render_arm_frame(const Tree& tree, const ArmShape& shape, const Eigen::VectorXd& q, const Camera& camera,
                         const ArmDrawStyle& style, double t = std::numeric_limits<double>::quiet_NaN(),
                         std::span<const Vec3> tool_path = {}, std::span<const std::vector<Vec3>> more_paths = {});

struct ArmAnimationOptions {
  Camera camera;                    // automatic fields fitted to every frame together
  ArmDrawStyle style;
  double fps = 30;                  // video frames per second, > 0
  double speed = 1;                 // simulated seconds per second of video, > 0
  double trace_seconds = 1;         // the tool's path over this many simulated seconds before each
                                    // frame, fading; 0 = none, infinity = all of it
  std::string still_path;           // also a PNG of one frame ("" = none), written atomically
  double still_time = 0;            // s: the still shows the last sample at or before it (the first
                                    // sample when before the start)
};

struct ArmAnimationSummary {
  int frames = 0;                   // in the video
  int nonfinite_frames = 0;         // of them drawn with the warning instead of the arm
  double still_time = std::numeric_limits<double>::quiet_NaN();  // the still's sample time, s
};

// The samples a video shows: frame k is the last sample at or before times[0] + k speed / fps, for
// every such time up to times.back() (so at least one frame). Throws std::invalid_argument for no
// times, times not finite and ascending, fps or speed not > 0.
std::vector<int> arm_animation_samples(std::span<const double> times, double fps, double speed);

// Writes the video of the arm at the samples (times[i], qs.col(i)): the frames of
// arm_animation_samples, each rendered by render_arm_frame with the fitted view and the tool path of
// the last trace_seconds (at most ~300 points, evenly thinned). The container follows the extension
// (".avi": Motion-JPEG; ".mp4": mp4v or avc1; plotting/animate.hpp's render_animation), written to an
// exclusive temporary beside it and renamed when complete. With options.still_path, the PNG of the frame at
// still_time too (same view). Throws std::invalid_argument for qs.rows() != nv, qs.cols() !=
// times.size() and the errors of arm_animation_samples and render_arm_frame; std::runtime_error
// naming the path when a file cannot be written.
ArmAnimationSummary write_arm_animation(const Tree& tree, const ArmShape& shape, std::span<const double> times,
                                        const Eigen::Ref<const Eigen::MatrixXd>& qs, const std::string& video_path,
                                        const ArmAnimationOptions& options = {});

// Only the PNG of one frame (options.still_path ignored): the sample at or before `t`, drawn exactly as
// write_arm_animation draws it (the view fitted to all samples, the tool path). Returns its sample time.
double write_arm_still(const Tree& tree, const ArmShape& shape, std::span<const double> times,
                       const Eigen::Ref<const Eigen::MatrixXd>& qs, double t, const std::string& png_path,
                       const ArmAnimationOptions& options = {});

}  // namespace ff
