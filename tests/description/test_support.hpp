// Helpers of the description tests: numbered documents with one line changed, the one error a reader
// throws, and the comparison of two trees body by body.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "common/errors.hpp"
#include "multibody/tree.hpp"

namespace ff::test {

inline std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string s; std::getline(in, s);) lines.push_back(s);
  return lines;
}

inline std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  return text;
}

// `text` with line `n` (1-based) replaced by `replacement` (which may hold several lines, or none).
inline std::string with_line(const std::string& text, int n, const std::string& replacement) {
  auto lines = split_lines(text);
  EXPECT_GE(n, 1);
  EXPECT_LE(n, static_cast<int>(lines.size()));
  lines.at(static_cast<std::size_t>(n - 1)) = replacement;
  return join_lines(lines);
}

// The ConfigError `read` throws (a failed expectation when it throws nothing or something else).
inline ConfigError config_error(const std::function<void()>& read) {
  try {
    read();
  } catch (const ConfigError& e) {
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ConfigError: " << e.what();
    return ConfigError("", 0, "", e.what());
  }
  ADD_FAILURE() << "no error";
  return ConfigError("", 0, "", "no error");
}

// Every derived field of every body the same to `tol`.
inline void expect_same_tree(const Tree& a, const Tree& b, double tol) {
  ASSERT_EQ(a.num_bodies(), b.num_bodies());
  ASSERT_EQ(a.nv(), b.nv());
  EXPECT_LE((a.gravity() - b.gravity()).cwiseAbs().maxCoeff(), tol);
  for (int i = 0; i < a.num_bodies(); ++i) {
    const Body& x = a.body(i);
    const Body& y = b.body(i);
    SCOPED_TRACE("body " + std::to_string(i) + " (" + x.name + ")");
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.parent, y.parent);
    EXPECT_EQ(x.joint, y.joint);
    EXPECT_EQ(x.dof, y.dof);
    EXPECT_LE((x.X_tree.E - y.X_tree.E).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((x.X_tree.r - y.X_tree.r).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((x.inertia - y.inertia).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((x.axis - y.axis).cwiseAbs().maxCoeff(), tol);
    EXPECT_LE((x.S - y.S).cwiseAbs().maxCoeff(), tol);
    EXPECT_NEAR(x.mass, y.mass, tol);
    EXPECT_NEAR(x.armature, y.armature, tol);
    EXPECT_NEAR(x.stiffness, y.stiffness, tol);
    EXPECT_NEAR(x.damping, y.damping, tol);
    EXPECT_NEAR(x.spring_reference, y.spring_reference, tol);
  }
}

}  // namespace ff::test
