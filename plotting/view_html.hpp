// A self-contained HTML 3-D viewer of arm runs (three.js, inlined: opens from file:// with no network;
// docs/viewer.md). The page plays variants[0] as a solid arm and the other variants in step with it as
// translucent ghosts (a Monte Carlo spread), among the world's shapes, over a ground grid perpendicular to
// `up`; the camera is fitted to everything and orbits with the mouse. Controls: a time slider, play/pause,
// speed, the deflection exaggeration k (1 to 100, log slider), ghosts on/off and their opacity, "jump to
// worst". variants[0]'s worst clearance pair is drawn within 2 % of the duration of its time: the capsule
// (and the shape, or the other capsule) red and a red line between the closest points; the status line
// says the time, the label and the minimum clearance. The URL hash "#t=1.25&exaggeration=10" sets both
// and pauses; once the first frame is drawn, <html> gets data-view-ready (window.flexfarmViewReady); a
// JavaScript error shows as a red banner (and data-view-error on <html>).
//
// Size: each variant is thinned evenly to at most kViewMaxFrames samples (its first and last kept, and
// the one nearest its worst_time), the ghosts together to at most kViewMaxGhostFrames (each at least
// kViewMinGhostFrames); positions are written to 6 significant digits, times exactly. The page is ~0.8 MB
// (three.js) plus ~60 bytes per capsule and frame (twice that with rigid_ends differing from ends).
#pragma once

#include <Eigen/Dense>

#include <array>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace ff {

inline constexpr int kViewMaxFrames = 2000, kViewMaxGhostFrames = 20000, kViewMinGhostFrames = 50;

// One obstacle of the world. All positions in the base frame, m.
struct ViewShape {
  std::string name;
  std::string type;             // "box", "sphere", "cylinder", "capsule", "bore", "plane", "mesh"
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();  // shape frame in the base frame
  Eigen::Vector3d size = Eigen::Vector3d::Zero();      // box: full edge lengths along x, y, z
  double radius = 0, length = 0;  // sphere/cylinder/capsule/bore: radius; cylinder/capsule/bore: length along
                                  // local z, centred on the origin (a capsule's: between its cap centres)
  std::vector<Eigen::Vector3f> vertices;              // mesh, shape frame
  std::vector<std::array<int, 3>> triangles;          // mesh, indices into vertices
};
// "bore" is the free space inside a cylinder (a tank's wall, a riser's bore): drawn as a translucent open tube.
// "plane" is a half-space whose boundary is the shape frame's xy plane (normal +z): drawn as a translucent
// square of three times the scene's diagonal, with its outline.

// One collision capsule of the arm (a body or a link segment).
struct ViewCapsule {
  std::string name;
  double radius = 0;  // m
};

struct ViewVariant {
  std::string label;                    // e.g. "variant 12: payload.mass=40"
  std::vector<double> t;                // sample times, s, finite and increasing
  std::vector<float> ends;              // samples x capsules x 6: [ax ay az bx by bz], the capsule's two end
                                        // points (non-finite: the capsule is not drawn at that sample)
  std::vector<float> rigid_ends;        // same layout with the elastic (flexible-link) dofs at zero; empty =
                                        // same as ends. Shown = rigid + k (ends - rigid), k the exaggeration.
  std::vector<float> tool;              // samples x 3: the tool point (its path drawn as a line, not
                                        // exaggerated), may be empty
  double min_clearance = std::numeric_limits<double>::quiet_NaN();  // m; its pair and time:
  int worst_capsule = -1, worst_shape = -1;  // -1 = none; worst_shape may also be -(k+2) for capsule k of
                                             // the same variant (arm-to-arm)
  double worst_time = std::numeric_limits<double>::quiet_NaN();     // s
  Eigen::Vector3d worst_a = Eigen::Vector3d::Zero(), worst_b = Eigen::Vector3d::Zero();  // the closest
                                        // points (capsule side, shape side) at worst_time
};

struct ViewScene {
  std::string title;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  // against gravity, base frame
  std::vector<ViewShape> shapes;
  std::vector<ViewCapsule> capsules;
  std::vector<ViewVariant> variants;    // variants[0] is played solid; the others are ghosts (translucent)
};

// Writes the page to `path` atomically (an exclusive temporary, then renamed). Throws std::invalid_argument for an
// inconsistent scene (no variants, array sizes not matching the samples and capsules, times not finite
// and increasing, an unknown shape type, an index out of range, a non-finite pose, radius or up),
// std::runtime_error naming the path when it cannot be written.
void write_view_html(const ViewScene& scene, const std::string& path);

// Text for HTML: & < > " as entities (the viewer's page, and the run report's).
std::string html_escape(std::string_view s);

}  // namespace ff
