#include "jobs/batches.hpp"

#include <map>
#include <stdexcept>
#include <tuple>

namespace ff {

namespace {
// Everything two lanes of one batch must share.
using Shape = std::tuple<int, int, int, double, double, int, int, int>;
Shape shape_of(const Model& m) {
  const int sections = m.spec.notch.enabled ? 2 * m.spec.notch.order + 1 : 0;
  const int drive_parts = (m.spec.hydraulics.enabled ? 1 : 0) + (m.spec.drive.enabled ? 2 : 0) +
                          (m.spec.friction.model == "lugre" ? 4 : 0);
  const auto& ss = m.spec.sensors;  // recorded sensors: the trace columns
  const int recorded = (ss.strain_gauge.enabled ? 1 : 0) + (ss.tip_accelerometer.enabled ? 2 : 0) +
                       (ss.tip_position.enabled ? 4 : 0);
  return {m.nseg, sections, m.substeps, m.control_period, m.duration, static_cast<int>(m.spec.simulation.integrator),
          drive_parts, recorded};
}
}  // namespace

std::vector<Batch> make_batches(const std::vector<Model>& models, const std::vector<int>& pending, int lanes) {
  if (lanes < 1) throw std::invalid_argument("make_batches: lanes must be >= 1");
  std::vector<Batch> out;
  std::map<Shape, std::size_t> open;  // shape -> its batch still filling
  for (int i : pending) {
    const Shape s = shape_of(models[i]);
    auto it = open.find(s);
    if (it == open.end() || static_cast<int>(out[it->second].variants.size()) == lanes) {
      out.push_back({});
      it = open.insert_or_assign(s, out.size() - 1).first;
    }
    out[it->second].variants.push_back(i);
  }
  return out;
}

}  // namespace ff
