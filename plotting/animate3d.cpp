// The 3-D arm view (animate3d.hpp): the arm's drawable geometry from the tree's forward kinematics,
// a pinhole camera, pieces drawn far to near with the shared canvas.hpp toolkit, the video through
// canvas::write_video.
#include "plotting/animate3d.hpp"

#include "multibody/algorithms.hpp"
#include "plotting/canvas.hpp"

#include <algorithm>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <tuple>

namespace ff {
namespace {

using namespace canvas;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------- geometry

// Which bodies the shape's flexible links own (index of the link, -1 = a rigid body), checked.
struct ShapeIndex {
  std::vector<int> link_of;       // per body
  std::vector<bool> elastic;      // per dof
  std::vector<std::vector<int>> chain;  // per link: its bodies root to tip
  std::vector<std::vector<int>> children;
  double heaviest = 0;            // the heaviest rigid body's mass, kg
};

ShapeIndex index_shape(const Tree& tree, const ArmShape& shape) {
  const int n = tree.num_bodies();
  ShapeIndex x;
  x.link_of.assign(size_t(n), -1);
  x.elastic.assign(size_t(tree.nv()), false);
  x.children.resize(size_t(n));
  const auto body_ok = [&](int b) { return b >= 0 && b < n; };
  if (shape.tool_body >= n || shape.tool_body < -1)
    throw std::invalid_argument("ArmShape: tool body " + std::to_string(shape.tool_body) + " outside the tree's " +
                                std::to_string(n) + " bodies");
  for (const auto& [body, point] : shape.more_tools)
    if (!body_ok(body))
      throw std::invalid_argument("ArmShape: tool body " + std::to_string(body) + " outside the tree's " +
                                  std::to_string(n) + " bodies");
  for (size_t l = 0; l < shape.flexible_links.size(); ++l) {
    const FlexibleLinkShape& f = shape.flexible_links[l];
    const std::string what = "ArmShape: flexible link " + std::to_string(l);
    if (!body_ok(f.root_body) || !body_ok(f.tip_body)) throw std::invalid_argument(what + ": a body outside the tree");
    std::vector<int> chain;
    for (int b = f.tip_body;; b = tree.body(b).parent) {
      if (b < 0) throw std::invalid_argument(what + ": its tip is not below its root");
      chain.push_back(b);
      if (b == f.root_body) break;
    }
    std::reverse(chain.begin(), chain.end());
    for (int b : chain) x.link_of[size_t(b)] = int(l);
    for (int d : f.elastic_dofs) {
      if (d < 0 || d >= tree.nv()) throw std::invalid_argument(what + ": elastic dof " + std::to_string(d) + " out of range");
      x.elastic[size_t(d)] = true;
    }
    x.chain.push_back(std::move(chain));
  }
  for (int i = 0; i < n; ++i) {
    if (tree.body(i).parent >= 0) x.children[size_t(tree.body(i).parent)].push_back(i);
    if (x.link_of[size_t(i)] < 0) x.heaviest = std::max(x.heaviest, tree.body(i).mass);
  }
  return x;
}

struct Capsule {
  Vec3 a, b;
};
struct Sphere {
  Vec3 centre;
  double mass;
};

// The drawable arm at one joint state (elastic dofs already exaggerated).
struct Geometry {
  std::vector<Capsule> links;             // rigid links
  std::vector<Capsule> base_links;        // from the base origin to the root joints
  std::vector<Sphere> masses;
  std::vector<std::vector<Vec3>> flexible;
  std::vector<Vec3> joints;
  Vec3 tool = Vec3::Constant(kNaN);
  std::vector<Vec3> more_tools;           // ArmShape::more_tools
  void points(std::vector<Vec3>& out) const {
    for (const auto* set : {&links, &base_links})
      for (const Capsule& c : *set) out.push_back(c.a), out.push_back(c.b);
    for (const Sphere& s : masses) out.push_back(s.centre);
    for (const auto& pl : flexible) out.insert(out.end(), pl.begin(), pl.end());
    for (const Vec3& j : joints) out.push_back(j);
    if (tool.allFinite()) out.push_back(tool);
    for (const Vec3& t : more_tools) out.push_back(t);
    out.push_back(Vec3::Zero());  // the base
  }
};

Eigen::VectorXd exaggerated(const ShapeIndex& x, const Eigen::Ref<const Eigen::VectorXd>& q, double factor) {
  Eigen::VectorXd out = q;
  if (factor != 1)
    for (size_t d = 0; d < x.elastic.size(); ++d)
      if (x.elastic[d]) out[Eigen::Index(d)] *= factor;
  return out;
}

Geometry arm_geometry(const Tree& tree, const ArmShape& shape, const ShapeIndex& x, const Eigen::VectorXd& q) {
  const int n = tree.num_bodies();
  std::vector<Pose> poses(static_cast<size_t>(n));
  calc_body_poses(tree, q, poses);
  const auto joint_origin = [&](int i) {
    const Body& b = tree.body(i);
    return b.parent < 0 ? b.X_tree.position() : poses[size_t(b.parent)].point(b.X_tree.position());
  };
  const auto add = [](std::vector<Capsule>& to, const Vec3& a, const Vec3& b) {
    if ((a - b).norm() > 1e-9) to.push_back({a, b});
  };
  const auto link_tip = [&](int l) {
    const FlexibleLinkShape& f = shape.flexible_links[size_t(l)];
    return poses[size_t(f.tip_body)].point(f.tip_point);
  };
  Geometry g;
  for (int i = 0; i < n; ++i) {
    const Body& b = tree.body(i);
    const Pose& p = poses[size_t(i)];
    const int link = x.link_of[size_t(i)];
    if (b.parent < 0) add(g.base_links, Vec3::Zero(), joint_origin(i));
    if (b.joint != JointType::kFixed && !x.elastic[size_t(b.dof)]) g.joints.push_back(joint_origin(i));
    // Where this body's own drawing ends for its children: the tip for a link's tip segment.
    const bool at_tip = link >= 0 && shape.flexible_links[size_t(link)].tip_body == i;
    const Vec3 from = at_tip ? link_tip(link) : p.position;
    bool leaf = true;
    for (int c : x.children[size_t(i)]) {
      if (link >= 0 && x.link_of[size_t(c)] == link) continue;  // inside the link: the polyline
      leaf = false;
      add(g.links, from, joint_origin(c));
    }
    if (link >= 0) continue;
    if (b.mass > 0) {
      g.masses.push_back({p.point(b.com), b.mass});
      if (leaf) add(g.links, p.position, p.point(b.com));
    }
    if (i == shape.tool_body) add(g.links, p.position, p.point(shape.tool_point));
    for (const auto& [body, point] : shape.more_tools)
      if (i == body) add(g.links, p.position, p.point(point));
  }
  for (size_t l = 0; l < x.chain.size(); ++l) {
    std::vector<Vec3> pl;
    for (int b : x.chain[l])
      if (pl.empty() || (pl.back() - poses[size_t(b)].position).norm() > 1e-9) pl.push_back(poses[size_t(b)].position);
    pl.push_back(link_tip(int(l)));
    g.flexible.push_back(std::move(pl));
  }
  if (shape.tool_body >= 0) g.tool = poses[size_t(shape.tool_body)].point(shape.tool_point);
  for (const auto& [body, point] : shape.more_tools) g.more_tools.push_back(poses[size_t(body)].point(point));
  return g;
}

// The horizontal axes: e1 = base x laid on the ground (base y when x is vertical), e2 = up x e1.
std::pair<Vec3, Vec3> ground_axes(const Vec3& up) {
  Vec3 e1 = Vec3::UnitX() - up * up.x();
  if (e1.norm() < 1e-6) e1 = Vec3::UnitY() - up * up.y();
  e1.normalize();
  return {e1, up.cross(e1)};
}

// ---------------------------------------------------------------- painting

cv::Scalar darker(const cv::Scalar& c, double t) { return mix(c, cv::Scalar(0, 0, 0), t); }
cv::Scalar lighter(const cv::Scalar& c, double t) { return mix(c, cv::Scalar(kWhite), t); }

struct Piece {
  double depth;
  std::function<void(cv::Mat&)> draw;
};

// A pixel-space capsule (round ends, radius r0 at p0 to r1 at p1), filled.
void fill_capsule(cv::Mat& img, cv::Point2d p0, cv::Point2d p1, double r0, double r1, const cv::Scalar& c) {
  cv::circle(img, fixed_point(p0), int(std::lround(std::max(r0, 0.5) * 16)), c, cv::FILLED, cv::LINE_AA, kShift);
  cv::circle(img, fixed_point(p1), int(std::lround(std::max(r1, 0.5) * 16)), c, cv::FILLED, cv::LINE_AA, kShift);
  const cv::Point2d d = p1 - p0;
  const double len = std::hypot(d.x, d.y);
  if (len < 1e-9) return;
  const cv::Point2d nrm(-d.y / len, d.x / len);
  const std::vector<cv::Point> quad{fixed_point(p0 + nrm * r0), fixed_point(p1 + nrm * r1), fixed_point(p1 - nrm * r1),
                                    fixed_point(p0 - nrm * r0)};
  cv::fillConvexPoly(img, quad, c, cv::LINE_AA, kShift);
}

struct Painter {
  const CameraView& v;
  Style st;
  double near_depth, fade_from, fade_to, fade;
  std::vector<Piece> pieces;
  std::vector<std::tuple<Vec3, Vec3, double>> tubes;  // the tubes' segments (base frame) and piece depths

  // A piece at `c` of radius r sits on the tubes that pass within r of it (a joint ring where links meet,
  // a mass on its link, the tool dot at a tip): it is drawn after them whatever the tubes' mean depths.
  double on_tubes(const Vec3& c, double r, double depth) const {
    for (const auto& [a, b, d] : tubes) {
      const Vec3 ab = b - a;
      const double t = std::clamp((c - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
      if ((a + t * ab - c).norm() <= r) depth = std::min(depth, d - 1e-9);
    }
    return depth;
  }

  cv::Scalar faded(const cv::Scalar& c, double depth) const {
    return lighter(c, fade * std::clamp((depth - fade_from) / (fade_to - fade_from), 0.0, 1.0));
  }
  // The segment cut to the part in front of the near plane; false when none is.
  bool clip(Vec3& a, Vec3& b) const {
    const double da = (a - v.eye).dot(v.forward), db = (b - v.eye).dot(v.forward);
    if (da < near_depth && db < near_depth) return false;
    if (da < near_depth) a = a + (b - a) * ((near_depth - da) / (db - da));
    if (db < near_depth) b = b + (a - b) * ((near_depth - db) / (da - db));
    return true;
  }
  cv::Point2d px(const Projected& p) const { return {p.x, p.y}; }
  double radius_px(double r, double depth) const { return v.focal * r / depth; }

  // A shaded tube: dark outline, fill, a light stripe on its upper side.
  void tube(const std::vector<Vec3>& points, double r, const cv::Scalar& colour) {
    std::vector<std::pair<Projected, Projected>> segs;
    double depth = 0;
    for (size_t i = 0; i + 1 < points.size(); ++i) {
      Vec3 a = points[i], b = points[i + 1];
      if (!clip(a, b)) continue;
      segs.emplace_back(project(v, a), project(v, b));
      depth += (segs.back().first.depth + segs.back().second.depth) / 2;
    }
    if (segs.empty()) return;
    depth /= double(segs.size());
    for (size_t i = 0; i + 1 < points.size(); ++i) tubes.emplace_back(points[i], points[i + 1], depth);
    const cv::Scalar fill = faded(colour, depth), edge = darker(fill, 0.45), shine = lighter(fill, 0.4);
    const double outline = std::max(1.0, st.s * 1.5);
    pieces.push_back({depth, [=, this](cv::Mat& img) {
                        for (const auto& [a, b] : segs)
                          fill_capsule(img, px(a), px(b), radius_px(r, a.depth) + outline, radius_px(r, b.depth) + outline, edge);
                        for (const auto& [a, b] : segs)
                          fill_capsule(img, px(a), px(b), radius_px(r, a.depth), radius_px(r, b.depth), fill);
                        for (const auto& [a, b] : segs) {
                          const double ra = radius_px(r, a.depth), rb = radius_px(r, b.depth);
                          cv::Point2d d = px(b) - px(a);
                          const double len = std::hypot(d.x, d.y);
                          if (len < 1e-9 || std::min(ra, rb) < 2.5) continue;
                          cv::Point2d nrm(-d.y / len, d.x / len);
                          if (nrm.y > 0) nrm = -nrm;  // the lit side faces up the image
                          const int th = std::max(1, int(std::lround(0.3 * std::min(ra, rb))));
                          cv::line(img, fixed_point(px(a) + nrm * (0.4 * ra)), fixed_point(px(b) + nrm * (0.4 * rb)), shine, th,
                                   cv::LINE_AA, kShift);
                        }
                      }});
  }
  void sphere(const Vec3& c, double r, const cv::Scalar& colour) {
    const Projected p = project(v, c);
    if (p.depth < near_depth + r) return;
    const double R = radius_px(r, p.depth);
    const cv::Scalar fill = faded(colour, p.depth), edge = darker(fill, 0.5), shine = lighter(fill, 0.55);
    const double outline = std::max(1.0, st.s * 1.5);
    pieces.push_back({on_tubes(c, r, p.depth - r), [=, this](cv::Mat& img) {
                        cv::circle(img, fixed_point(px(p)), int(std::lround((R + outline) * 16)), edge, cv::FILLED, cv::LINE_AA, kShift);
                        cv::circle(img, fixed_point(px(p)), int(std::lround(R * 16)), fill, cv::FILLED, cv::LINE_AA, kShift);
                        cv::circle(img, fixed_point(px(p) + cv::Point2d(-0.35 * R, -0.35 * R)), int(std::lround(0.3 * R * 16)), shine,
                                   cv::FILLED, cv::LINE_AA, kShift);
                      }});
  }
  // A joint: a dark ring with a white centre, drawn over the links that meet there.
  void ring(const Vec3& c, double r) {
    const Projected p = project(v, c);
    if (p.depth < near_depth + r) return;
    const double R = std::max(radius_px(r, p.depth), 2.0);
    const cv::Scalar edge = faded(cv::Scalar(kTextColour), p.depth), centre = faded(cv::Scalar(kWhite), p.depth);
    pieces.push_back({on_tubes(c, r, p.depth - r), [=, this](cv::Mat& img) {
                        cv::circle(img, fixed_point(px(p)), int(std::lround(R * 16)), edge, cv::FILLED, cv::LINE_AA, kShift);
                        cv::circle(img, fixed_point(px(p)), int(std::lround(0.45 * R * 16)), centre, cv::FILLED, cv::LINE_AA, kShift);
                      }});
  }
  // A thin line of a fixed pixel width (grid, trace, axes).
  void line(Vec3 a, Vec3 b, const cv::Scalar& colour, int th, bool fade_it = true, double bias = 0) {
    if (!clip(a, b)) return;
    const Projected pa = project(v, a), pb = project(v, b);
    const double depth = (pa.depth + pb.depth) / 2;
    const cv::Scalar c = fade_it ? faded(colour, depth) : colour;
    pieces.push_back({depth - bias, [=, this](cv::Mat& img) {
                        cv::line(img, fixed_point(px(pa)), fixed_point(px(pb)), c, th, cv::LINE_AA, kShift);
                      }});
  }
  // Draws the pieces far to near (stable: equal depths keep their order) and forgets them.
  void paint(cv::Mat& img) {
    std::stable_sort(pieces.begin(), pieces.end(), [](const Piece& a, const Piece& b) { return a.depth > b.depth; });
    for (const Piece& p : pieces) p.draw(img);
    pieces.clear();
    tubes.clear();
  }
};

// The arm's palette roles.
cv::Scalar link_colour() { return bgr(palette_colour(0)); }      // blue
cv::Scalar flexible_colour() { return bgr(palette_colour(4)); }  // orange
cv::Scalar tool_colour() { return bgr(palette_colour(1)); }      // vermillion
cv::Scalar path_colour() { return bgr(palette_colour(3)); }      // reddish purple
cv::Scalar mass_colour() { return {150, 150, 150}; }             // steel grey
cv::Scalar base_colour() { return kFrameColour; }

// A point dropped straight down (along -up) onto the ground.
Vec3 on_ground(const Vec3& p, const Vec3& up, double ground) { return p - (p.dot(up) - ground) * up; }

void check_camera(const Camera& c) {
  check_image_size("Camera", c.width, c.height, 240, 240);
  if (!std::isfinite(c.azimuth) || !(std::abs(c.elevation) <= 90 * kDegree + 1e-12) ||
      !(c.fov > 0 && c.fov < 180 * kDegree))
    throw std::invalid_argument("Camera: the azimuth must be finite, the elevation within [-90, 90] degrees and the "
                                "field of view within (0, 180) degrees");
}

bool automatic(double v) { return !(v > 0) || !std::isfinite(v); }

}  // namespace

// ---------------------------------------------------------------- camera

Vec3 up_direction(const Tree& tree) {
  const double g = tree.gravity().norm();
  return g > 0 ? Vec3(-tree.gravity() / g) : Vec3::UnitZ();
}

CameraView camera_view(const Camera& c, const Vec3& up_in) {
  check_camera(c);
  if (!(c.distance > 0) || !std::isfinite(c.distance) || !c.target.allFinite())
    throw std::invalid_argument("camera_view: the distance must be > 0 and the target finite (fit_arm_view fills them)");
  const Vec3 up = up_in.normalized();
  const auto [e1, e2] = ground_axes(up);
  CameraView v;
  const Vec3 dir = std::cos(c.elevation) * (std::cos(c.azimuth) * e1 + std::sin(c.azimuth) * e2) + std::sin(c.elevation) * up;
  v.eye = c.target + c.distance * dir;
  v.forward = -dir;
  v.right = -std::sin(c.azimuth) * e1 + std::cos(c.azimuth) * e2;  // = forward x up, normalised; level even
                                                                     // straight from above or below
  v.up = v.right.cross(v.forward);
  v.focal = (c.height / 2.0) / std::tan(c.fov / 2);
  v.cx = (c.width - 1) / 2.0, v.cy = (c.height - 1) / 2.0;
  v.width = c.width, v.height = c.height;
  return v;
}

Projected project(const CameraView& v, const Vec3& p) {
  const Vec3 d = p - v.eye;
  const double depth = d.dot(v.forward);
  return {v.cx + v.focal * d.dot(v.right) / depth, v.cy - v.focal * d.dot(v.up) / depth, depth};
}

// ---------------------------------------------------------------- fit

void fit_arm_view(const Tree& tree, const ArmShape& shape, const Eigen::Ref<const Eigen::MatrixXd>& qs, Camera& camera,
                  ArmDrawStyle& style) {
  if (qs.rows() != tree.nv())
    throw std::invalid_argument("fit_arm_view: q has " + std::to_string(qs.rows()) + " rows, the tree " +
                                std::to_string(tree.nv()) + " dofs");
  check_camera(camera);
  const ShapeIndex x = index_shape(tree, shape);
  const double factor = std::isfinite(style.exaggeration) ? style.exaggeration : 1.0;
  std::vector<Vec3> pts;
  for (Eigen::Index k = 0; k < qs.cols(); ++k)
    if (qs.col(k).allFinite()) arm_geometry(tree, shape, x, exaggerated(x, qs.col(k), factor)).points(pts);
  if (pts.empty()) arm_geometry(tree, shape, x, Eigen::VectorXd::Zero(tree.nv())).points(pts);
  Vec3 lo = pts[0], hi = pts[0];
  for (const Vec3& p : pts) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Vec3 centre = (lo + hi) / 2;
  const double radius = std::max(0.5 * (hi - lo).norm(), 0.05);
  const Vec3 up = up_direction(tree);

  if (automatic(style.link_radius)) style.link_radius = radius / 70;
  if (automatic(style.sphere_radius)) style.sphere_radius = 2.6 * style.link_radius;
  if (!std::isfinite(style.ground)) {
    style.ground = pts[0].dot(up);
    for (const Vec3& p : pts) style.ground = std::min(style.ground, p.dot(up));
  }
  if (!style.grid_centre.allFinite()) style.grid_centre = on_ground(centre, up, style.ground);
  if (automatic(style.grid_half_size)) style.grid_half_size = 1.4 * radius;
  if (automatic(style.grid_step)) style.grid_step = nice_tick_step(0, 2 * style.grid_half_size, 8);

  if (!camera.target.allFinite()) camera.target = centre;
  if (automatic(camera.distance)) {
    // The bounding sphere (about the target) inside the narrower of the two fields of view, with a margin.
    double reach = 0;
    for (const Vec3& p : pts) reach = std::max(reach, (p - camera.target).norm());
    reach = std::max(reach, 0.05);
    const double half = std::min(camera.fov / 2, std::atan(std::tan(camera.fov / 2) * camera.width / camera.height));
    camera.distance = 1.25 * reach / std::sin(half);  // room for the title band and the base axes
  }
}

Vec3 arm_tool_position(const Tree& tree, const ArmShape& shape, const Eigen::Ref<const Eigen::VectorXd>& q,
                       double exaggeration) {
  if (shape.tool_body < 0 || q.size() != tree.nv() || !q.allFinite()) return Vec3::Constant(kNaN);
  const ShapeIndex x = index_shape(tree, shape);
  return calc_point_position(tree, exaggerated(x, q, exaggeration), shape.tool_body, shape.tool_point);
}

Vec3 arm_more_tool_position(const Tree& tree, const ArmShape& shape, std::size_t k,
                            const Eigen::Ref<const Eigen::VectorXd>& q, double exaggeration) {
  if (k >= shape.more_tools.size() || q.size() != tree.nv() || !q.allFinite()) return Vec3::Constant(kNaN);
  const ShapeIndex x = index_shape(tree, shape);
  return calc_point_position(tree, exaggerated(x, q, exaggeration), shape.more_tools[k].first, shape.more_tools[k].second);
}

// ---------------------------------------------------------------- frame

cv::Mat render_arm_frame(const Tree& tree, const ArmShape& shape, const Eigen::VectorXd& q, const Camera& camera_in,
                         const ArmDrawStyle& style_in, double t, std::span<const Vec3> tool_path,
                         std::span<const std::vector<Vec3>> more_paths) {
  if (q.size() != tree.nv())
    throw std::invalid_argument("render_arm_frame: q has " + std::to_string(q.size()) + " values, the tree " +
                                std::to_string(tree.nv()) + " dofs");
  const ShapeIndex x = index_shape(tree, shape);
  Camera camera = camera_in;
  ArmDrawStyle style = style_in;
  if (!std::isfinite(style.exaggeration)) throw std::invalid_argument("render_arm_frame: exaggeration must be finite");
  const bool finite = q.allFinite();
  fit_arm_view(tree, shape, q, camera, style);  // only the automatic fields
  const CameraView v = camera_view(camera, up_direction(tree));
  const Vec3 up = up_direction(tree);
  const auto [e1, e2] = ground_axes(up);

  cv::Mat img(camera.height, camera.width, CV_8UC3, kWhite);
  const double to_target = (camera.target - v.eye).norm();
  Painter p{v,
            style_at(std::clamp(std::min(camera.width, camera.height) / 800.0, 0.45, 4.0)),
            0.02 * to_target,
            to_target - style.grid_half_size,
            to_target + style.grid_half_size,
            std::clamp(style.depth_fade, 0.0, 1.0),
            {},
            {}};
  const Style& st = p.st;

  // The ground: grid lines, then the shadows (all on it, so under everything else).
  {
    const double h = style.grid_half_size, step = style.grid_step;
    const int n = std::min(400, int(std::floor(h / step + 1e-9)));
    const Vec3 c = style.grid_centre;
    for (int i = -n; i <= n; ++i) {
      const cv::Scalar colour = i == 0 ? cv::Scalar(200, 200, 200) : cv::Scalar(222, 222, 222);
      p.line(c + e1 * (i * step) - e2 * h, c + e1 * (i * step) + e2 * h, colour, 1);
      p.line(c + e2 * (i * step) - e1 * h, c + e2 * (i * step) + e1 * h, colour, 1);
    }
    p.paint(img);
  }
  const Geometry g = finite ? arm_geometry(tree, shape, x, exaggerated(x, q, style.exaggeration)) : Geometry{};
  const double r = style.link_radius;
  if (finite && style.shadows) {
    const cv::Scalar shade(208, 208, 208);
    const auto down = [&](const Vec3& a) { return on_ground(a, up, style.ground); };
    Painter s = p;
    s.fade = 0;
    for (const auto* set : {&g.base_links, &g.links})
      for (const Capsule& c : *set) {
        Vec3 a = down(c.a), b = down(c.b);
        if (!s.clip(a, b)) continue;
        const Projected pa = project(v, a), pb = project(v, b);
        fill_capsule(img, s.px(pa), s.px(pb), s.radius_px(r, pa.depth), s.radius_px(r, pb.depth), shade);
      }
    for (const auto& pl : g.flexible)
      for (size_t i = 0; i + 1 < pl.size(); ++i) {
        Vec3 a = down(pl[i]), b = down(pl[i + 1]);
        if (!s.clip(a, b)) continue;
        const Projected pa = project(v, a), pb = project(v, b);
        fill_capsule(img, s.px(pa), s.px(pb), s.radius_px(0.8 * r, pa.depth), s.radius_px(0.8 * r, pb.depth), shade);
      }
  }

  // The base: axes x, y, z one grid step long, a dark plate at the origin and a post down to the ground.
  {
    const double a = style.grid_step;
    const int th = std::max(2, st.px(2.5));
    p.line(Vec3::Zero(), Vec3::UnitX() * a, bgr(palette_colour(1)), th);
    p.line(Vec3::Zero(), Vec3::UnitY() * a, bgr(palette_colour(2)), th);
    p.line(Vec3::Zero(), Vec3::UnitZ() * a, bgr(palette_colour(0)), th);
    const Vec3 foot = on_ground(Vec3::Zero(), up, style.ground);
    if ((foot).norm() > 1e-9) p.tube({foot, Vec3::Zero()}, 0.6 * r, base_colour());
    std::vector<Vec3> rim;
    for (int i = 0; i < 32; ++i) {
      const double th2 = 2 * 3.14159265358979323846 * i / 32;
      rim.push_back(3.2 * r * (std::cos(th2) * e1 + std::sin(th2) * e2));
    }
    bool visible = true;
    std::vector<cv::Point> poly;
    for (const Vec3& q3 : rim) {
      const Projected pr = project(v, q3);
      visible &= pr.depth > p.near_depth;
      poly.push_back(fixed_point({pr.x, pr.y}));
    }
    const Projected o = project(v, Vec3::Zero());
    if (visible) {
      const cv::Scalar c = p.faded(base_colour(), o.depth);
      p.pieces.push_back({o.depth + 3.2 * r, [poly, c](cv::Mat& m) { cv::fillPoly(m, std::vector<std::vector<cv::Point>>{poly}, c, cv::LINE_AA, kShift); }});
    }
  }

  // Each tool's path, fading from the newest point back.
  const auto draw_path = [&](std::span<const Vec3> path) {
    if (path.size() < 2) return;
    const int th = std::max(2, st.px(2.5));
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      if (!path[i].allFinite() || !path[i + 1].allFinite()) continue;
      const double age = 1.0 - double(i + 1) / double(path.size() - 1);  // 0 = newest
      p.line(path[i], path[i + 1], lighter(path_colour(), 0.85 * age), th, false, r);
    }
  };
  draw_path(tool_path);
  for (const std::vector<Vec3>& path : more_paths) draw_path(path);

  // The arm.
  if (finite) {
    for (const Capsule& c : g.base_links) p.tube({c.a, c.b}, 0.9 * r, base_colour());
    for (const Capsule& c : g.links) p.tube({c.a, c.b}, r, link_colour());
    for (const auto& pl : g.flexible) p.tube(pl, 0.8 * r, flexible_colour());
    for (const Sphere& s : g.masses)
      p.sphere(s.centre, std::max(style.sphere_radius * std::cbrt(s.mass / std::max(x.heaviest, 1e-300)), 1.2 * r), mass_colour());
    for (const Vec3& j : g.joints) p.ring(j, 1.6 * r);
    if (g.tool.allFinite()) p.sphere(g.tool, 1.1 * r, tool_colour());
    for (const Vec3& tool : g.more_tools)
      if (tool.allFinite()) p.sphere(tool, 1.1 * r, tool_colour());
  }
  p.paint(img);

  // Text: the title, the time stamp, the grid step, the exaggeration; the warning.
  int y = st.pad;
  const std::string title = hershey_text(style.title);
  if (!title.empty()) {
    put_text(img, title, {img.cols / 2, y}, HAlign::centre, VAlign::top, fitted(title, st.title, img.cols - 2 * st.pad),
             kTextColour);
    y += line_height(st.title) + st.gap;
  }
  if (std::isfinite(t)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "t = %.3f s", t);
    put_text(img, buf, {st.pad, y}, HAlign::left, VAlign::top, st.label, kTextColour);
  }
  const int bottom = img.rows - st.pad;
  put_text(img, "grid " + format_tick(style.grid_step, style.grid_step) + " m", {st.pad, bottom}, HAlign::left,
           VAlign::bottom, st.label, kTextColour);
  if (style.exaggeration != 1) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "deflection x %g", style.exaggeration);
    put_text(img, buf, {img.cols - st.pad, bottom}, HAlign::right, VAlign::bottom, st.label, kTextColour);
  }
  if (!finite) {
    const std::string warn = "non-finite joint state: arm not drawn";
    const Font f = fitted(warn, st.title, img.cols - 4 * st.pad);
    const TextSize ts = measure(warn, f);
    const cv::Point c(img.cols / 2, img.rows / 2);
    cv::rectangle(img, {c.x - ts.width / 2 - st.gap, c.y - ts.ascent / 2 - st.gap},
                  {c.x + ts.width / 2 + st.gap, c.y + ts.ascent / 2 + ts.descent + st.gap}, kWhite, cv::FILLED);
    put_text(img, warn, c, HAlign::centre, VAlign::middle, f, bgr(palette_colour(1)));
  }
  return img;
}

// ---------------------------------------------------------------- video

std::vector<int> arm_animation_samples(std::span<const double> times, double fps, double speed) {
  if (times.empty()) throw std::invalid_argument("arm animation: no samples");
  for (size_t i = 0; i < times.size(); ++i)
    if (!std::isfinite(times[i]) || (i > 0 && !(times[i] > times[i - 1])))
      throw std::invalid_argument("arm animation: the sample times must be finite and ascending (sample " +
                                  std::to_string(i) + ")");
  if (!(fps > 0) || !std::isfinite(fps) || !(speed > 0) || !std::isfinite(speed))
    throw std::invalid_argument("arm animation: fps and speed must be > 0");
  const double t0 = times.front(), span = times.back() - t0, dt = speed / fps;
  const long frames = long(std::floor(span / dt * (1 + 1e-12) + 1e-9)) + 1;
  if (frames > 10'000'000) throw std::invalid_argument("arm animation: more than 10^7 frames");
  std::vector<int> out;
  out.reserve(size_t(frames));
  size_t i = 0;
  for (long k = 0; k < frames; ++k) {
    const double tk = t0 + double(k) * dt;
    const double tol = 1e-9 * std::max(1.0, std::abs(tk));
    while (i + 1 < times.size() && times[i + 1] <= tk + tol) ++i;
    out.push_back(int(i));
  }
  return out;
}

namespace {

// The fitted view and the tool positions of every sample, shared by the video and the still.
struct Prepared {
  Camera camera;
  ArmDrawStyle style;
  std::vector<Vec3> tool;  // per sample
  std::vector<std::vector<Vec3>> more_tools;  // per ArmShape::more_tools, per sample
};

Prepared prepare(const Tree& tree, const ArmShape& shape, std::span<const double> times,
                 const Eigen::Ref<const Eigen::MatrixXd>& qs, const ArmAnimationOptions& o) {
  if (qs.rows() != tree.nv() || size_t(qs.cols()) != times.size())
    throw std::invalid_argument("arm animation: q is " + std::to_string(qs.rows()) + " x " + std::to_string(qs.cols()) +
                                ", want " + std::to_string(tree.nv()) + " x " + std::to_string(times.size()) +
                                " (dofs x samples)");
  if (!std::isfinite(o.style.exaggeration)) throw std::invalid_argument("arm animation: exaggeration must be finite");
  Prepared p{o.camera, o.style, {}, {}};
  fit_arm_view(tree, shape, qs, p.camera, p.style);
  camera_view(p.camera, up_direction(tree));  // reject a bad camera before any file is touched
  p.tool.reserve(times.size());
  for (Eigen::Index k = 0; k < qs.cols(); ++k) p.tool.push_back(arm_tool_position(tree, shape, qs.col(k), p.style.exaggeration));
  p.more_tools.resize(shape.more_tools.size());
  for (std::size_t t = 0; t < shape.more_tools.size(); ++t)
    for (Eigen::Index k = 0; k < qs.cols(); ++k)
      p.more_tools[t].push_back(arm_more_tool_position(tree, shape, t, qs.col(k), p.style.exaggeration));
  return p;
}

cv::Mat frame_at(const Tree& tree, const ArmShape& shape, std::span<const double> times,
                 const Eigen::Ref<const Eigen::MatrixXd>& qs, const ArmAnimationOptions& o, const Prepared& p, int i) {
  // Each tool's positions over the last trace_seconds, oldest first (at most ~300 points).
  const auto recent = [&](const std::vector<Vec3>& positions) {
    std::vector<Vec3> path;
    if (o.trace_seconds <= 0) return path;
    int first = i;
    while (first > 0 && times[size_t(i)] - times[size_t(first - 1)] <= o.trace_seconds) --first;
    const int stride = std::max(1, (i - first) / 300);
    for (int j = i; j >= first; j -= stride) path.push_back(positions[size_t(j)]);
    std::reverse(path.begin(), path.end());
    return path;
  };
  const std::vector<Vec3> path = shape.tool_body >= 0 ? recent(p.tool) : std::vector<Vec3>{};
  std::vector<std::vector<Vec3>> more;
  for (const std::vector<Vec3>& positions : p.more_tools) more.push_back(recent(positions));
  return render_arm_frame(tree, shape, qs.col(i), p.camera, p.style, times[size_t(i)], path, more);
}

int sample_at(std::span<const double> times, double t) {
  const auto it = std::upper_bound(times.begin(), times.end(), t + 1e-9 * std::max(1.0, std::abs(t)));
  return it == times.begin() ? 0 : int(it - times.begin()) - 1;
}

}  // namespace

ArmAnimationSummary write_arm_animation(const Tree& tree, const ArmShape& shape, std::span<const double> times,
                                        const Eigen::Ref<const Eigen::MatrixXd>& qs, const std::string& video_path,
                                        const ArmAnimationOptions& o) {
  const std::vector<int> samples = arm_animation_samples(times, o.fps, o.speed);
  const Prepared p = prepare(tree, shape, times, qs, o);
  ArmAnimationSummary sum;
  sum.frames = int(samples.size());
  for (int i : samples) sum.nonfinite_frames += !qs.col(i).allFinite();
  write_video("write_arm_animation", video_path, o.fps, cv::Size(p.camera.width, p.camera.height), sum.frames,
              [&](int k) { return frame_at(tree, shape, times, qs, o, p, samples[size_t(k)]); });
  if (!o.still_path.empty()) {
    const int i = sample_at(times, o.still_time);
    write_png("write_arm_animation", frame_at(tree, shape, times, qs, o, p, i), o.still_path);
    sum.still_time = times[size_t(i)];
  }
  return sum;
}

double write_arm_still(const Tree& tree, const ArmShape& shape, std::span<const double> times,
                       const Eigen::Ref<const Eigen::MatrixXd>& qs, double t, const std::string& png_path,
                       const ArmAnimationOptions& o) {
  arm_animation_samples(times, o.fps, o.speed);  // the same checks as the video
  const Prepared p = prepare(tree, shape, times, qs, o);
  const int i = sample_at(times, t);
  write_png("write_arm_still", frame_at(tree, shape, times, qs, o, p, i), png_path);
  return times[size_t(i)];
}

}  // namespace ff
