#include "validate/synthetic.hpp"

#include <cmath>
#include <stdexcept>

#include "common/random.hpp"
#include "kernel/sensors.hpp"
#include "kernel/simulate.hpp"
#include "validate/residuals.hpp"

namespace ff {

Record make_synthetic_record(const Model& truth, double noise, std::uint64_t seed, int decimate) {
  if (decimate < 1) throw std::invalid_argument("make_synthetic_record: decimate must be >= 1");
  const BatchModel bm = make_batch(std::span<const Model>(&truth, 1));
  const BatchRun run = simulate(bm);
  if (run.status[0] != LaneStatus::kOk) throw std::runtime_error("the truth model failed to run");
  const Trace& tr = run.traces[0];
  Record r;
  r.source = "<synthetic>";
  // The output channels as their sensors (sensors.hub_torque ...) measured them.
  const std::vector<double> torque = measure_output(truth, kOutHubTorque, tr.torque, true);
  const std::vector<double> tip = measure_output(truth, kOutTipDeflection, tr.tip_deflection, true);
  // The in-loop channels as logged (sensors.*.logged): what the controller read, or on time.
  std::vector<std::pair<const char*, std::vector<double>>> cols = {
      {"ref", tr.ref},
      {"hub_torque", torque},
      {"hub_angle", log_loop_channel(truth, kLoopHubAngle, tr.hub_angle, true)},
      {"hub_rate", log_loop_channel(truth, kLoopHubRate, tr.hub_rate, true)},
      {"tip_deflection", tip}};
  for (const auto& [name, x] : tr.extra)
    if (const OutputChannel c = find_output_channel(name); c != kOutputChannels)
      cols.emplace_back(output_channel_name(c), measure_output(truth, c, x, true));
  for (std::size_t k = 0; k < tr.t.size(); k += decimate) r.t.push_back(tr.t[k]);
  std::uint64_t channel = 0;
  for (const auto& [name, y] : cols) {
    auto& out = r.columns[name];
    for (std::size_t k = 0; k < tr.t.size(); k += decimate) out.push_back(y[k]);
    ++channel;
    if (std::string(name) == "ref" || noise <= 0) continue;
    const double sd = noise * calc_standard_deviation(out);
    CounterRng rng(calc_variant_seed(seed, channel));
    for (double& x : out) x += sd * rng.normal();
  }
  return r;
}

}  // namespace ff
