#include <cmath>

#include "apps/verbs.hpp"
#include "kernel/model_io.hpp"
#include "kernel/simulate.hpp"
#include "kernel/yaml_reader.hpp"
#include "plotting/plot.hpp"
#include "sweep/paths.hpp"

namespace ff {

Model load_model_with(const std::string& path, const std::vector<std::string>& sets) {
  std::vector<Assignment> assignments;
  for (const auto& s : sets) assignments.push_back(parse_assignment(s));
  return make_model_with(load_yaml_file(path), path, assignments);
}

void write_trace_plots(const std::string& dir, const std::vector<std::string>& labels,
                       const std::vector<const Trace*>& traces, const std::string& title) {
  struct Signal {
    const char* file;
    const char* axis;
    double scale;
    const std::vector<double> Trace::*member;
  };
  const Signal signals[] = {
      {"tip_angle", "tip angle (rad)", 1.0, &Trace::tip_angle},
      {"hub_angle", "hub angle (rad)", 1.0, &Trace::hub_angle},
      {"tip_deflection", "tip deflection (mm)", 1e3, &Trace::tip_deflection},
      {"hub_torque", "hub torque (kN m)", 1e-3, &Trace::torque},
  };
  for (const auto& sig : signals) {
    LinePlot p;
    p.title = title + ": " + std::string(sig.axis).substr(0, std::string(sig.axis).find(" ("));
    p.x_label = "time (s)";
    p.y_label = sig.axis;
    for (std::size_t i = 0; i < traces.size(); ++i) {
      Series s;
      s.label = labels[i];
      s.x = traces[i]->t;
      s.y = traces[i]->*sig.member;
      for (auto& y : s.y) y *= sig.scale;
      p.series.push_back(std::move(s));
    }
    render_line_plot(p, dir + "/" + sig.file + ".png");
  }
}

}  // namespace ff
