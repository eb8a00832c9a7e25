// What an arm can touch (docs/formats.md, "World"): each body's collision capsules, derived from its
// geometry, and the clearances at a pose to the world's obstacles (world/world.hpp) and between arms.
//
// Capsules, in the body's frame (the `collision:` block overrides a part's radius or leaves it out):
//   a rigid body with mass   one capsule from its origin to each of: each child's joint origin, twice its
//                            centre of mass (a uniform body's far end), each tool point on it (points at
//                            the origin, repeated or on another's segment dropped; none left: a sphere
//                            at the origin); radius
//                            sqrt(d' I d / m), I its inertia about the centre of mass and d the capsule's
//                            direction (a thin tube's outer radius), a sphere's sqrt(5 tr(I) / 6 m);
//   a flexible link          per segment body, from its origin to its child's joint origin (the tip
//                            segment: to the beam's end), radius sqrt((I_y + I_z) / A) of the section
//                            (a thin tube's outer radius; a solid rod's is sqrt(2) times it);
//   massless bodies          none (the cells' and rotors' frames).
// A part is a rigid body or a whole flexible link (its segments): the unit the clearance columns name.
// Pairs between arms: capsules of two parts on different branches of the tree (neither body an
// ancestor of the other), e.g. the two arms of a dual arm; a chain's own links are not paired.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "multibody/algorithms.hpp"  // Pose
#include "multibody/tree.hpp"
#include "world/world.hpp"

namespace ff {

struct ArmModel;

struct CollisionCapsule {
  int body = -1;
  int part = -1;                  // index into ArmCollision::parts
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();  // the segment's ends in the body's frame, m
  double radius = 0.0;            // m
};

// A part's override (`collision: {NAME: {radius, enabled}}`).
struct CollisionPartSpec {
  std::string name;               // a rigid body's or a flexible link's
  double radius = 0.0;            // m; 0 = derived
  bool enabled = true;            // false: no capsules (the part touches nothing)
  int line = 0;
};

struct ArmCollision {
  World world;
  std::vector<std::string> parts;   // the parts with capsules, in the order of their first body
  std::vector<CollisionCapsule> capsules;
  std::vector<std::pair<int, int>> arm_pairs;  // capsule indices, first < second
  // Whether the run measures clearances: capsules, and obstacles or pairs between arms.
  bool active() const { return !capsules.empty() && (!world.empty() || !arm_pairs.empty()); }
  // Trace columns beyond the deflections (active only): "clearance", then "<part>.clearance" per part,
  // "<obstacle>.clearance" per obstacle.
  std::size_t columns() const { return active() ? 1 + parts.size() + world.obstacles.size() : 0; }
};

// The capsules of an arm's tree, its parts and its pairs between arms. Throws ConfigError naming the
// model file (`collision.NAME`) for an override naming no part, and (`world.NAME`) for an obstacle
// named as a part.
ArmCollision make_arm_collision(const ArmModel& m, World world, const std::vector<CollisionPartSpec>& overrides);

// The least clearance at a pose and its pair: capsule `capsule` and obstacle `obstacle` (-1: another
// capsule, `other`), the closest points, base frame.
struct ArmClearanceWitness {
  double distance = std::numeric_limits<double>::infinity();
  int capsule = -1, obstacle = -1, other = -1;
  Vec3 on_arm = Vec3::Zero(), on_other = Vec3::Zero();
};

// The clearances at the body poses: out[0] the least of all, out[1 + p] part p's least (to the world
// and the other arms), out[1 + parts + o] obstacle o's least (to any part); +infinity where nothing
// constrains. The broad phase skips a pair whose bound cannot lower either column (exact: the same
// values as without it). `witness` (optional): the least pair.
void calc_arm_clearances(const ArmCollision& c, std::span<const Pose> poses, double* out,
                         ArmClearanceWitness* witness = nullptr);

// A capsule's ends in the base frame at the poses.
std::pair<Vec3, Vec3> calc_capsule_ends(const CollisionCapsule& k, std::span<const Pose> poses);

}  // namespace ff
