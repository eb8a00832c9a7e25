// The 3-D viewer page (view_html.hpp) of arm runs (arm/arm_simulate.hpp with ArmRunOptions::keep_q): the
// arm's collision capsules (arm/arm_collision.hpp) at every sample, with the flexible links and drive
// twists straight beside them for the page's deflection exaggeration, the tool's path, the world's
// obstacles and the run's least clearance pair. Header-only (reads the model's fields), as
// animate3d_arm.hpp, so ff_plotting does not link ff_arm; the caller links both. A part left out of the
// collision (`collision: {NAME: {enabled: false}}`) has no capsule and is not drawn.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "arm/arm_model.hpp"
#include "multibody/algorithms.hpp"
#include "plotting/animate3d.hpp"  // up_direction
#include "plotting/view_html.hpp"
#include "world/mesh.hpp"

namespace ff {

// The scene without variants: the title, up (against gravity), the world's obstacles and the capsules.
inline ViewScene make_arm_view_scene(const ArmModel& m, const std::string& title) {
  ViewScene s;
  s.title = title;
  s.up = up_direction(m.tree);
  for (const Obstacle& o : m.collision.world.obstacles) {
    ViewShape v;
    v.name = o.name;
    v.type = shape_type_name(o.type);
    v.pose.topLeftCorner<3, 3>() = o.rotation;
    v.pose.topRightCorner<3, 1>() = o.position;
    v.size = o.size;
    v.radius = o.radius;
    v.length = o.length;
    if (o.mesh) {
      for (const Vec3& p : o.mesh->vertices) v.vertices.push_back(p.cast<float>());
      v.triangles = o.mesh->triangles;
    }
    s.shapes.push_back(std::move(v));
  }
  std::vector<int> seen(m.collision.parts.size(), 0);
  for (const CollisionCapsule& k : m.collision.capsules) {
    const std::string& part = m.collision.parts[static_cast<std::size_t>(k.part)];
    s.capsules.push_back({part + "#" + std::to_string(seen[static_cast<std::size_t>(k.part)]++), k.radius});
  }
  return s;
}

// One run as a variant of the page: at sample i (times[i], qs.col(i)) each capsule's ends, those with the
// compliant dofs at zero, the first tool's point, and the least clearance over the run with its pair.
inline ViewVariant make_arm_view_variant(const ArmModel& m, std::span<const double> times,
                                         const Eigen::Ref<const Eigen::MatrixXd>& qs, const std::string& label) {
  ViewVariant v;
  v.label = label;
  v.t.assign(times.begin(), times.end());
  std::vector<Pose> poses(static_cast<std::size_t>(m.tree.num_bodies())), rigid(poses.size());
  std::vector<double> clearances(m.collision.columns());
  Eigen::VectorXd q_rigid;
  const auto push_ends = [](std::vector<float>& out, const std::pair<Vec3, Vec3>& e) {
    for (int i = 0; i < 3; ++i) out.push_back(static_cast<float>(e.first[i]));
    for (int i = 0; i < 3; ++i) out.push_back(static_cast<float>(e.second[i]));
  };
  for (std::size_t i = 0; i < times.size(); ++i) {
    const Eigen::VectorXd q = qs.col(static_cast<Eigen::Index>(i));
    if (!q.allFinite()) {  // a failed lane: nothing drawn from here
      v.ends.insert(v.ends.end(), 6 * m.collision.capsules.size(), NAN);
      v.rigid_ends.insert(v.rigid_ends.end(), 6 * m.collision.capsules.size(), NAN);
      v.tool.insert(v.tool.end(), 3, NAN);
      continue;
    }
    calc_body_poses(m.tree, q, poses);
    q_rigid = q;
    for (int d : m.compliant_dofs) q_rigid[d] = 0.0;
    calc_body_poses(m.tree, q_rigid, rigid);
    for (const CollisionCapsule& k : m.collision.capsules) {
      push_ends(v.ends, calc_capsule_ends(k, poses));
      push_ends(v.rigid_ends, calc_capsule_ends(k, rigid));
    }
    const Vec3 tool = poses[static_cast<std::size_t>(m.tool_body)].point(m.tool_point);
    for (int c = 0; c < 3; ++c) v.tool.push_back(static_cast<float>(tool[c]));
    if (!m.collision.active()) continue;
    ArmClearanceWitness w;
    calc_arm_clearances(m.collision, poses, clearances.data(), &w);
    if (w.capsule >= 0 && !(w.distance >= v.min_clearance)) {
      v.min_clearance = w.distance;
      v.worst_capsule = w.capsule;
      v.worst_shape = w.obstacle >= 0 ? w.obstacle : -(w.other + 2);
      v.worst_time = times[i];
      v.worst_a = w.on_arm;
      v.worst_b = w.on_other;
    }
  }
  return v;
}

}  // namespace ff
