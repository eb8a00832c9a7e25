// The 3-D arm view (animate3d.hpp) of an ArmModel (arm/arm_model.hpp): its flexible links and tool as
// an ArmShape, and the video of a run kept with ArmRunOptions::keep_q (arm/arm_simulate.hpp), e.g.
//   const ArmRun run = simulate_arms(std::span<const ArmModel>(&arm, 1), {.keep_q = true});
//   write_arm_animation(arm, run.traces[0].t(), run.q[0], "arm.avi", options);
// Header-only (reads the model's fields), so ff_plotting does not link ff_arm; the caller links both.
#pragma once

#include "arm/arm_model.hpp"
#include "plotting/animate3d.hpp"

namespace ff {

// The flexible links (their segment chains and elastic dofs) and the tool points of an arm (the first as
// tool_body/tool_point, the others as more_tools).
inline ArmShape arm_shape(const ArmModel& m) {
  ArmShape s;
  for (const LinkTip& l : m.links) s.flexible_links.push_back({l.root_body, l.tip_body, l.tip_point, l.elastic_dofs});
  s.tool_body = m.tool_body;
  s.tool_point = m.tool_point;
  for (std::size_t t = 1; t < m.tools.size(); ++t) s.more_tools.emplace_back(m.tools[t].body, m.tools[t].point);
  return s;
}

// write_arm_animation of the arm's tree and shape; the title defaults to the model's description (or
// its file's name).
inline ArmAnimationSummary write_arm_animation(const ArmModel& m, std::span<const double> times,
                                               const Eigen::Ref<const Eigen::MatrixXd>& qs,
                                               const std::string& video_path, ArmAnimationOptions options = {}) {
  if (options.style.title.empty()) options.style.title = m.spec.description.empty() ? m.spec.source : m.spec.description;
  return write_arm_animation(m.tree, arm_shape(m), times, qs, video_path, options);
}

// write_arm_still of the arm's tree and shape (the PNG of the frame at t), the same default title.
inline double write_arm_still(const ArmModel& m, std::span<const double> times,
                              const Eigen::Ref<const Eigen::MatrixXd>& qs, double t, const std::string& png_path,
                              ArmAnimationOptions options = {}) {
  if (options.style.title.empty()) options.style.title = m.spec.description.empty() ? m.spec.source : m.spec.description;
  return write_arm_still(m.tree, arm_shape(m), times, qs, t, png_path, options);
}

// The arm at q (render_arm_frame with the arm's shape).
inline cv::Mat render_arm_frame(const ArmModel& m, const Eigen::VectorXd& q, const Camera& camera,
                                const ArmDrawStyle& style, double t = std::numeric_limits<double>::quiet_NaN(),
                                std::span<const Vec3> tool_path = {}) {
  return render_arm_frame(m.tree, arm_shape(m), q, camera, style, t, tool_path);
}

}  // namespace ff
