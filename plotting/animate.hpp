// Video of the arm seen from above, rendered with OpenCV (which stays out of this header): hub,
// segments as thick lines, joints as dots, payload as a square at the tip, the undeformed radial
// line dashed, the tip's path so far, a time stamp and a scale bar in metres. The view (scale and
// centre) is fixed over the whole video so motion is not hidden by re-zooming.
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace ff {

struct ArmFrame {
  double t;                  // s
  std::vector<double> x, y;  // joint/tip points in the world frame, m: x[0], y[0] the hub axis (0, 0), last = tip
  double hub_angle = NAN;    // rad; NaN = direction of the first segment, p1 − p0 (the hub carries it rigidly)
};

struct Animation {
  std::string title;
  std::vector<ArmFrame> frames;  // at the video frame rate
  double fps = 30;
  double exaggeration = 1.0;     // scale the deflection from the hub's radial line (1 = true shape)
  bool tip_trace = true;         // draw the tip's path so far
  int width = 960, height = 960; // px, at least 240 × 240
};

// The hub angle of a frame: `hub_angle` if finite, else the direction of p1 − p0 (of p0 if the
// frame has a single point). Throws std::invalid_argument for an empty frame.
double arm_hub_angle(const ArmFrame& f);

// Exaggerates the deflection of one point p (relative to the hub at the origin): with the radial
// unit vector u = (cos θ, sin θ) and the lateral n = (−sin θ, cos θ) of hub angle θ,
//   p = r·u + l·n  ->  r·u + factor·l·n,
// i.e. the radial component is kept and the lateral offset from the hub's radial line scaled, so
// a straight beam along the radial line stays straight and factor 1 is the identity.
void exaggerate_point(double& x, double& y, double hub_angle, double factor);
// The frame with every point exaggerated about the frame's hub angle (arm_hub_angle).
ArmFrame exaggerate_frame(const ArmFrame& f, double factor);

// Writes the video. The container and codec follow the extension: ".mp4"/".m4v"/".mov" try
// mp4v then avc1 (FFmpeg); anything else — normally ".avi" — is Motion-JPEG in AVI (FFmpeg, then
// OpenCV's built-in writer). If no mp4 codec opens, Motion-JPEG/AVI data is written under the
// requested name (players detect the content). The file is written to an exclusive temporary
// beside it with the container's extension (the writers pick the container from it) and renamed to `video_path` when complete.
// Throws std::runtime_error naming the path when it cannot be written or no codec works, and
// std::invalid_argument for no frames, a frame with mismatched x/y, fps <= 0 or a too small size.
void render_animation(const Animation& a, const std::string& video_path);
// One frame as an RGB buffer (row-major, 3 bytes per pixel, width × height), for tests and
// previews. Throws std::out_of_range for a frame index outside the animation.
std::vector<unsigned char> render_animation_frame(const Animation& a, int frame);

}  // namespace ff
