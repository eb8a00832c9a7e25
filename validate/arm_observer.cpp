#include "validate/arm_observer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "kernel/sensors.hpp"
#include "validate/arm_record.hpp"

namespace ff {

namespace {

using std::size_t;

// The least noise std the observer assumes on a channel, in its unit (rad, rad/s, m, N m): below any
// real sensor's (a 24-bit encoder's quantum is 3.7e-7 rad).
constexpr double kArmNoiseFloor = 1e-8;

// The model the gain is designed on: the replay model's smooth part (static Coulomb friction and
// stiction, the sensors' quantisation left out: a central difference across a tanh of width 1e-3 rad/s
// or a quantum sees a slope the moving arm does not have). The shape is the model's (copy_arm_lane).
ArmModel make_design_arm(const ArmModel& m) {
  ArmModel d = m;
  for (ActuatedJoint& a : d.actuated) {
    FrictionSpec& f = a.control.friction;
    if (f.model == "static") f.coulomb = f.stiction = 0.0;
    a.control.angle_sensor.resolution = 0.0;
    a.control.rate_sensor.resolution = 0.0;
  }
  return d;
}

// design_steady_gain on the balanced problem x = D x', y = S y' (D_i = sqrt(Q1_ii), 1 where it is 0;
// S_c = sqrt(R_cc)): the arm's angles, rates and the tool's metres differ in their noise by up to ten
// orders of magnitude, and unbalanced the doubling's tolerances, relative to |P|, see only the largest.
// The gain and pole radius are those of the original problem (a similarity: L = D L' S^-1).
void design_balanced_gain(const Eigen::MatrixXd& A1, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q1,
                          ObserverDesign& d) {
  Eigen::VectorXd D = Q1.diagonal().cwiseSqrt();
  for (Eigen::Index i = 0; i < D.size(); ++i)
    if (!(D[i] > 0.0)) D[i] = 1.0;
  const Eigen::VectorXd S = d.R.diagonal().cwiseSqrt();
  ObserverDesign b;
  b.period = d.period;
  b.R = Eigen::MatrixXd::Identity(d.R.rows(), d.R.cols());
  const Eigen::MatrixXd Ab = D.cwiseInverse().asDiagonal() * A1 * D.asDiagonal();
  const Eigen::MatrixXd Cb = S.cwiseInverse().asDiagonal() * C * D.asDiagonal();
  const Eigen::MatrixXd Qb = D.cwiseInverse().asDiagonal() * Q1 * D.cwiseInverse().asDiagonal();
  design_steady_gain(Ab, Cb, Qb, b);
  d.ok = b.ok;
  d.message = b.message;
  d.doublings = b.doublings;
  d.pole_radius = b.pole_radius;
  d.C = C;
  if (!b.ok) return;
  d.L = D.asDiagonal() * b.L * S.cwiseInverse().asDiagonal();
  d.P = D.asDiagonal() * b.P * D.asDiagonal();
}

// The lanes one model's linearisations run on: 2 nx perturbed copies of its observer lane, in runs of
// at most kMaxTreeLanes lanes, made once.
struct DesignLanes {
  std::vector<ArmModel> models;       // (W) the design model
  std::unique_ptr<ArmLanes> lanes;
};

struct Linearisation {
  bool ok = true;
  Eigen::MatrixXd A, C;  // dx_{k+1}/dx_k (nx x nx), dy_k/dx_k (ny x nx)
};

// A and C at lane l of `obs` at sample k (before the controllers' sample k): its copies x0 +- delta_i e_i
// run sample k, y_k read from their outputs, x_{k+1} from their state.
Linearisation linearise(const ArmLanes& obs, int l, long k, const std::vector<size_t>& columns, DesignLanes& d,
                        std::vector<double>& x) {
  const int nx = calc_arm_state_size(obs), ny = static_cast<int>(columns.size()), lanes = 2 * nx;
  get_arm_state(obs, l, x.data());
  const Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(x.data(), nx);
  const Eigen::VectorXd delta = make_difference_steps(x0);
  Eigen::MatrixXd x1(nx, lanes), y0(ny, lanes);
  Linearisation lin;
  ArmLanes& a = *d.lanes;
  for (int first = 0; first < lanes; first += a.W) {
    for (int j = 0; j < a.W; ++j) {
      copy_arm_lane(obs, l, a, j);
      const int i = std::min(first + j, lanes - 1) / 2;  // lane 2i: +delta_i, 2i + 1: -delta_i
      for (int m = 0; m < nx; ++m) x[m] = x0[m];
      x[i] += (first + j) % 2 == 0 ? delta[i] : -delta[i];
      set_arm_state(a, j, x.data());
    }
    step_arm_controllers(a, k);
    for (int j = 0; j < a.W && first + j < lanes; ++j)
      for (int c = 0; c < ny; ++c) y0(c, first + j) = a.row[columns[c] * static_cast<size_t>(a.W) + static_cast<size_t>(j)];
    step_arm_plant(a, k);
    for (int j = 0; j < a.W && first + j < lanes; ++j) {
      lin.ok = lin.ok && a.status[static_cast<size_t>(j)] == LaneStatus::kOk;
      get_arm_state(a, j, x.data());
      x1.col(first + j) = Eigen::Map<const Eigen::VectorXd>(x.data(), nx);
    }
  }
  lin.A = calc_central_differences(x1, delta);
  lin.C = calc_central_differences(y0, delta);
  lin.ok = lin.ok && lin.A.allFinite() && lin.C.allFinite();
  return lin;
}

}  // namespace

std::vector<std::string> arm_observer_channels(const ArmModel& m, const Record& r) {
  std::vector<std::string> out;
  auto take = [&](const std::string& c) {
    if (r.has(c) && !is_constant_column(r.at(c))) out.push_back(c);
  };
  for (const ActuatedJoint& a : m.actuated) {
    take(a.name + ".angle");
    take(a.name + ".rate");
    if (a.control.hydraulics.enabled) take(a.name + ".torque");
  }
  for (const std::string& c : arm_record_columns(m))
    if (is_arm_tool_column(m, c) || c.find(".deflection_") != std::string::npos) take(c);
  return out;
}

ArmObserverRun run_arm_observer(std::span<const ArmModel> models, const Record& r, int k_ahead,
                                const ArmObserverOptions& options) {
  if (k_ahead < 0) throw std::invalid_argument("run_arm_observer: k_ahead must be >= 0");
  if (models.empty()) throw std::invalid_argument("run_arm_observer: no models");
  if (!(options.process_noise > 0.0) || !std::isfinite(options.process_noise))
    throw std::invalid_argument("the observer's process noise must be a positive number (rad/s^2)");
  if (!(options.relinearise > 0.0) || !std::isfinite(options.relinearise))
    throw std::invalid_argument("the observer's re-linearisation interval must be a positive number of seconds");
  const int M = static_cast<int>(models.size());
  ArmReplaySetup setup = prepare_arm_replay(models, r);
  // Lanes 0..M-1: the observer; M..2M-1: the k-step predictions.
  std::vector<ArmModel> lane_models = setup.lanes;
  if (k_ahead > 0)
    for (int l = 0; l < M; ++l) lane_models.push_back(setup.lanes[static_cast<size_t>(l)]);
  ArmRunOptions run_options;
  run_options.reference = &setup.ref;
  ArmLanes obs = make_arm_lanes(lane_models, run_options);
  const int nx = calc_arm_state_size(obs), W = obs.W;
  const long ns = obs.samples;
  const double T = obs.T;
  if (!options.initial_state.empty() && static_cast<int>(options.initial_state.size()) != nx)
    throw std::invalid_argument("run_arm_observer: the initial state needs " + std::to_string(nx) + " values");

  ArmObserverRun out;
  out.nx = nx;
  out.resampled = setup.resampled;
  // The measured channels, their record columns and their columns in the lanes' outputs.
  const std::vector<long> measured = find_measured_samples(r, T, ns);
  const int period = calc_measurement_period(measured);
  const int every = std::max(1, static_cast<int>(std::lround(options.relinearise / T)));
  ArmObserverDesign base;
  base.channels = arm_observer_channels(models.front(), r);
  base.process_noise = options.process_noise;
  base.period = period;
  base.relinearise = every;
  ObserverDesign gain;  // R and the noise; per model its latest gain
  gain.channels = base.channels;
  gain.period = period;
  set_measurement_noise(r, gain);
  // At least kArmNoiseFloor in the channel's unit (a noise-free record's smooth channels give R down
  // to 1e-22 and a Riccati equation doubling cannot solve to its tolerance).
  for (Eigen::Index c = 0; c < gain.R.rows(); ++c) {
    gain.R(c, c) = std::max(gain.R(c, c), kArmNoiseFloor * kArmNoiseFloor);
    gain.noise_std[static_cast<size_t>(c)] = std::sqrt(gain.R(c, c));
  }
  base.noise_std = gain.noise_std;
  const int ny = static_cast<int>(base.channels.size());
  std::vector<size_t> columns;
  std::vector<const std::vector<double>*> record_column;
  for (const std::string& c : base.channels) {
    const std::string tn = arm_trace_name(c);
    columns.push_back(static_cast<size_t>(std::find(obs.names.begin(), obs.names.end(), tn) - obs.names.begin()));
    record_column.push_back(&r.at(c));
  }
  if (ny == 0) base.message = "the record has no measured channel that varies";
  // The joints' angles and rates as each lane's model logs them, brought back on time (a column logged as
  // read is d + L controller samples late, kernel/sensors.hpp unlog_channel): the correction compares them
  // with the state now. Empty: the record's own column.
  std::vector<std::vector<std::vector<double>>> on_time(static_cast<size_t>(M), std::vector<std::vector<double>>(static_cast<size_t>(ny)));
  for (size_t l = 0; l < on_time.size(); ++l)
    for (size_t c = 0; c < on_time[l].size(); ++c)
      for (const ActuatedJoint& a : models[l].actuated) {
        const std::string& name = base.channels[c];
        const bool angle = name == a.name + ".angle";
        if (!angle && name != a.name + ".rate") continue;
        const LoopChannelSpec& ch = angle ? a.control.angle_sensor : a.control.rate_sensor;
        const int late = (is_logged_on_time(ch) ? 0 : ch.delay) + ch.logged_delay;
        if (late > 0)
          for (double t : r.t) on_time[l][c].push_back(interpolate(r.t, *record_column[c], t + late * T));
      }
  out.design.assign(static_cast<size_t>(M), base);
  std::vector<ObserverDesign> gains(static_cast<size_t>(M), gain);
  std::vector<char> have_gain(static_cast<size_t>(M), 0);
  const Eigen::MatrixXd Q1 = calc_process_noise(obs.nv, nx, T, options.process_noise, true);

  // Each model's linearisation lanes, made once.
  const int design_lanes = std::min(2 * nx, kMaxTreeLanes);
  std::vector<DesignLanes> design(static_cast<size_t>(M));
  for (int l = 0; l < M; ++l) {
    DesignLanes& d = design[static_cast<size_t>(l)];
    d.models.assign(static_cast<size_t>(design_lanes), make_design_arm(setup.lanes[static_cast<size_t>(l)]));
    d.lanes = std::make_unique<ArmLanes>(make_arm_lanes(d.models, run_options));
  }

  out.state.assign(static_cast<size_t>(M), std::vector<double>(static_cast<size_t>(ns) * nx));
  std::vector<ArmTrace> traces(static_cast<size_t>(W), make_arm_trace(obs));
  // Scratch, made once: nothing is allocated while the lanes step (a linearisation and its DARE do).
  std::vector<double> x(static_cast<size_t>(nx)), e(static_cast<size_t>(ny));
  for (long k = 0; k < ns; ++k) {
    if (k == 0 && !options.initial_state.empty())
      for (int l = 0; l < M; ++l) set_arm_state(obs, l, options.initial_state.data());
    // A k-step prediction starts from x(k|k-1) and the observer's controller states.
    if (k_ahead > 0 && k % k_ahead == 0)
      for (int l = 0; l < M; ++l) copy_arm_lane(obs, l, obs, M + l);
    // A new gain at x(k|k-1) every `every` samples.
    if (k % every == 0 && ny > 0)
      for (int l = 0; l < M; ++l) {
        if (obs.status[static_cast<size_t>(l)] != LaneStatus::kOk) continue;
        ArmObserverDesign& od = out.design[static_cast<size_t>(l)];
        const Linearisation lin = linearise(obs, l, k, columns, design[static_cast<size_t>(l)], x);
        ObserverDesign next = gains[static_cast<size_t>(l)];
        if (lin.ok) design_balanced_gain(lin.A, lin.C, Q1, next);
        if (!lin.ok || !next.ok) {
          if (k == 0) od.message = lin.ok ? next.message : "the model failed numerically in its linearisation";
          ++od.failed;
          continue;
        }
        if (k == 0) od.ok = true;
        gains[static_cast<size_t>(l)] = std::move(next);
        have_gain[static_cast<size_t>(l)] = 1;
        ++od.gains;
        od.pole_radius = std::max(od.pole_radius, gains[static_cast<size_t>(l)].pole_radius);
        od.doublings = std::max(od.doublings, gains[static_cast<size_t>(l)].doublings);
      }
    // The correction: x(k|k) = x(k|k-1) + L (y_k - h(x(k|k-1))).
    const long j = measured[static_cast<size_t>(k)];
    if (j >= 0) {
      calc_arm_outputs(obs);
      for (int l = 0; l < M; ++l) {
        if (!have_gain[static_cast<size_t>(l)] || obs.status[static_cast<size_t>(l)] != LaneStatus::kOk) continue;
        const Eigen::MatrixXd& L = gains[static_cast<size_t>(l)].L;
        for (int c = 0; c < ny; ++c)
          e[static_cast<size_t>(c)] = (on_time[static_cast<size_t>(l)][static_cast<size_t>(c)].empty()
                                           ? (*record_column[static_cast<size_t>(c)])[static_cast<size_t>(j)]
                                           : on_time[static_cast<size_t>(l)][static_cast<size_t>(c)][static_cast<size_t>(j)]) -
                                      obs.row[columns[static_cast<size_t>(c)] * static_cast<size_t>(W) + static_cast<size_t>(l)];
        get_arm_state(obs, l, x.data());
        for (int i = 0; i < nx; ++i)
          for (int c = 0; c < ny; ++c) x[static_cast<size_t>(i)] += L(i, c) * e[static_cast<size_t>(c)];
        set_arm_state(obs, l, x.data());
      }
    }
    for (int l = 0; l < M; ++l) get_arm_state(obs, l, out.state[static_cast<size_t>(l)].data() + k * nx);
    step_arm_controllers(obs, k);
    for (int l = 0; l < W; ++l) store_arm_row(obs, l, k, traces[static_cast<size_t>(l)]);
    if (k + 1 == ns) break;
    step_arm_plant(obs, k);
  }
  for (int l = 0; l < W; ++l)
    if (obs.status[static_cast<size_t>(l)] != LaneStatus::kOk) mark_arm_trace_failure(obs, traces[static_cast<size_t>(l)]);
  for (int l = 0; l < M; ++l) {
    ArmObserverDesign& od = out.design[static_cast<size_t>(l)];
    if (od.ok && od.failed > 0)
      od.message = std::to_string(od.failed) + " of " + std::to_string(od.gains + od.failed) +
                   " linearisations failed (the last gain kept)";
    out.estimate.push_back(std::move(traces[static_cast<size_t>(l)]));
    out.estimate_status.push_back(obs.status[static_cast<size_t>(l)]);
    if (k_ahead > 0) {
      out.k_step.push_back(std::move(traces[static_cast<size_t>(M + l)]));
      out.k_step_status.push_back(obs.status[static_cast<size_t>(M + l)]);
    }
  }
  return out;
}

}  // namespace ff
