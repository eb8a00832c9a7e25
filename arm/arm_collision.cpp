// Collision capsules and clearances of an arm (arm_collision.hpp).
#include "arm/arm_collision.hpp"

#include <algorithm>
#include <cmath>

#include "arm/arm_model.hpp"
#include "common/closest.hpp"
#include "common/errors.hpp"

namespace ff {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Whether body `a` is an ancestor of (or is) body `b`.
bool is_ancestor(const Tree& tree, int a, int b) {
  for (int i = b; i >= 0; i = tree.body(i).parent)
    if (i == a) return true;
  return false;
}

// The radius of a rigid body's capsule along unit d (zero d: a sphere's).
double rigid_radius(const Body& body, const Vec3& d) {
  if (!(body.mass > 0)) return 0.0;
  if (d.norm() == 0) return std::sqrt(5.0 * body.inertia_com.trace() / (6.0 * body.mass));
  return std::sqrt(std::max(0.0, d.dot(body.inertia_com * d)) / body.mass);
}

}  // namespace

ArmCollision make_arm_collision(const ArmModel& m, World world, const std::vector<CollisionPartSpec>& overrides) {
  ArmCollision c;
  c.world = std::move(world);
  const Tree& tree = m.tree;
  const int nb = tree.num_bodies();
  // The part of each body: its flexible link's, or its own (massless bodies none).
  std::vector<int> part(static_cast<std::size_t>(nb), -1);
  std::vector<double> link_radius;
  for (const LinkTip& l : m.links) {
    const int p = static_cast<int>(c.parts.size());
    c.parts.push_back(l.name);
    for (int i = l.root_body; i <= l.tip_body; ++i) part[static_cast<std::size_t>(i)] = p;
    const auto f = std::find_if(m.spec.tree.flexible_links.begin(), m.spec.tree.flexible_links.end(),
                                [&](const FlexibleLinkInfo& x) { return x.name == l.name; });
    const BeamSection& s = f->link.section;
    link_radius.push_back(std::sqrt((s.second_moment_y + s.second_moment_z) / s.area));
  }
  for (int i = 0; i < nb; ++i)
    if (part[static_cast<std::size_t>(i)] < 0 && tree.body(i).mass > 0) {
      part[static_cast<std::size_t>(i)] = static_cast<int>(c.parts.size());
      c.parts.push_back(tree.body(i).name);
    }
  // The overrides, by part name.
  std::vector<const CollisionPartSpec*> given(c.parts.size(), nullptr);
  for (const CollisionPartSpec& o : overrides) {
    const auto it = std::find(c.parts.begin(), c.parts.end(), o.name);
    if (it == c.parts.end()) {
      std::string known;
      for (const std::string& p : c.parts) known += (known.empty() ? "" : ", ") + p;
      throw ConfigError(m.spec.source, o.line, "collision." + o.name,
                        "no part of that name" + format_did_you_mean(o.name, c.parts) +
                            ": a rigid body with mass or a flexible link (" + known + ")");
    }
    given[static_cast<std::size_t>(it - c.parts.begin())] = &o;
  }
  for (const Obstacle& o : c.world.obstacles)
    if (std::find(c.parts.begin(), c.parts.end(), o.name) != c.parts.end())
      throw ConfigError(m.spec.source, o.line, "world." + o.name, "an obstacle's name must differ from the arm's parts' (it heads a column)");

  for (int i = 0; i < nb; ++i) {
    const int p = part[static_cast<std::size_t>(i)];
    if (p < 0) continue;
    const CollisionPartSpec* o = given[static_cast<std::size_t>(p)];
    if (o && !o->enabled) continue;
    const Body& body = tree.body(i);
    // The far ends: the children's joint origins, then (a rigid body) twice its centre of mass and its
    // tools, (a link's tip segment) the beam's end.
    std::vector<Vec3> ends;
    for (int j = i + 1; j < nb; ++j)
      if (tree.body(j).parent == i) ends.push_back(tree.body(j).X_tree.position());
    const bool flexible = p < static_cast<int>(m.links.size());
    if (flexible) {
      if (i == m.links[static_cast<std::size_t>(p)].tip_body) ends.push_back(m.links[static_cast<std::size_t>(p)].tip_point);
    } else {
      ends.push_back(2.0 * body.com);
      for (const ArmTool& t : m.tools)
        if (t.body == i) ends.push_back(t.point);
    }
    std::vector<Vec3> kept;
    for (const Vec3& e : ends)
      if (e.norm() > 1e-9 && std::none_of(kept.begin(), kept.end(), [&](const Vec3& k) { return (k - e).norm() <= 1e-9; }))
        kept.push_back(e);
    // An end on the segment to another (a tool point inside the link) adds nothing.
    std::erase_if(kept, [&](const Vec3& e) {
      return std::any_of(kept.begin(), kept.end(), [&](const Vec3& f) {
        return &f != &e && e.cross(f).norm() <= 1e-9 * f.squaredNorm() && e.dot(f) < f.squaredNorm();
      });
    });
    if (kept.empty() && !flexible) kept.push_back(Vec3::Zero());  // a sphere
    for (const Vec3& e : kept) {
      CollisionCapsule k;
      k.body = i, k.part = p, k.b = e;
      k.radius = o && o->radius > 0 ? o->radius
                 : flexible         ? link_radius[static_cast<std::size_t>(p)]
                                    : rigid_radius(body, e.norm() > 0 ? Vec3(e.normalized()) : Vec3::Zero());
      c.capsules.push_back(k);
    }
  }
  // Only parts with capsules have columns (one left out by `enabled: false` has none).
  std::vector<int> renumber(c.parts.size(), -1);
  std::vector<std::string> kept_parts;
  for (CollisionCapsule& k : c.capsules) {
    int& r = renumber[static_cast<std::size_t>(k.part)];
    if (r < 0) r = static_cast<int>(kept_parts.size()), kept_parts.push_back(c.parts[static_cast<std::size_t>(k.part)]);
    k.part = r;
  }
  c.parts = std::move(kept_parts);
  // Pairs between arms: bodies on different branches.
  for (std::size_t u = 0; u < c.capsules.size(); ++u)
    for (std::size_t v = u + 1; v < c.capsules.size(); ++v) {
      const int bu = c.capsules[u].body, bv = c.capsules[v].body;
      if (c.capsules[u].part == c.capsules[v].part || is_ancestor(tree, bu, bv) || is_ancestor(tree, bv, bu)) continue;
      c.arm_pairs.emplace_back(static_cast<int>(u), static_cast<int>(v));
    }
  return c;
}

std::pair<Vec3, Vec3> calc_capsule_ends(const CollisionCapsule& k, std::span<const Pose> poses) {
  const Pose& p = poses[static_cast<std::size_t>(k.body)];
  return {p.point(k.a), p.point(k.b)};
}

void calc_arm_clearances(const ArmCollision& c, std::span<const Pose> poses, double* out, ArmClearanceWitness* witness) {
  const std::size_t np = c.parts.size(), no = c.world.obstacles.size();
  std::fill(out, out + 1 + np + no, kInf);
  double* part = out + 1;
  double* obstacle = out + 1 + np;
  const auto note = [&](const Clearance& d, int capsule, int obs, int other) {
    if (witness && d.distance < witness->distance)
      *witness = {d.distance, capsule, obs, other, d.on_segment, d.on_obstacle};
  };
  if (witness) *witness = {};
  for (std::size_t k = 0; k < c.capsules.size(); ++k) {
    const CollisionCapsule& cap = c.capsules[k];
    const auto [a, b] = calc_capsule_ends(cap, poses);
    double& pk = part[cap.part];
    for (std::size_t o = 0; o < no; ++o) {
      const Obstacle& obs = c.world.obstacles[o];
      // The broad phase: skip when the bound cannot lower either column.
      if (calc_clearance_bound(obs, a, b, cap.radius) >= std::max(pk, obstacle[o])) continue;
      const Clearance d = calc_clearance(obs, a, b, cap.radius);
      pk = std::min(pk, d.distance);
      obstacle[o] = std::min(obstacle[o], d.distance);
      note(d, static_cast<int>(k), static_cast<int>(o), -1);
    }
  }
  for (const auto& [u, v] : c.arm_pairs) {
    const CollisionCapsule &cu = c.capsules[static_cast<std::size_t>(u)], &cv = c.capsules[static_cast<std::size_t>(v)];
    const auto [au, bu] = calc_capsule_ends(cu, poses);
    const auto [av, bv] = calc_capsule_ends(cv, poses);
    const Clearance d = calc_capsule_clearance(au, bu, cu.radius, av, bv, cv.radius);
    part[cu.part] = std::min(part[cu.part], d.distance);
    part[cv.part] = std::min(part[cv.part], d.distance);
    note(d, u, -1, v);
  }
  for (std::size_t p = 0; p < np; ++p) out[0] = std::min(out[0], part[p]);
}

}  // namespace ff
