// The size limits of kinematic trees and flexible links (docs/formats.md, "Kinematic trees"): the
// readers check them as they read (naming the line and key), make_tree and append_flexible_link again.
#pragma once

#include <cstddef>
#include <string>

namespace ff {

// The most bodies a tree may have, every link, drive rotor and flexible link's segment and joint body
// counted (a flexible link of N segments is 3N - 2 bodies; N when planar, 2N - 1 without torsion). An
// arm model's closed-loop modes are a dense eigenproblem of twice its dofs, their time and memory
// growing as the cube and the square of it.
inline constexpr int kMaxTreeBodies = 1000;

// The most segments a flexible link may have: 3N - 2 = 766 bodies, within kMaxTreeBodies. The lumping's
// error falls as 1/N^2 (0.01 % of the first modes at N = 48).
inline constexpr int kMaxFlexibleSegments = 256;

// "" when a tree of `bodies` bodies is within kMaxTreeBodies, else what is wrong (multibody/tree.cpp).
std::string tree_size_fault(std::size_t bodies);

}  // namespace ff
