#include "validate/observer.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "kernel/drive.hpp"
#include "kernel/dynamics.hpp"
#include "kernel/sensors.hpp"

namespace ff {

namespace {

enum class Channel { kHubAngle, kHubRate, kTipDeflection, kHubTorque };

Channel channel_of(const std::string& name) {
  if (name == "hub_angle") return Channel::kHubAngle;
  if (name == "hub_rate") return Channel::kHubRate;
  if (name == "tip_deflection") return Channel::kTipDeflection;
  if (name == "hub_torque") return Channel::kHubTorque;
  throw std::invalid_argument("the observer does not measure '" + name + "'");
}

// A trace's column of a measured channel (the same signals the record's columns are).
const std::vector<double>& trace_channel(const Trace& tr, Channel c) {
  switch (c) {
    case Channel::kHubAngle: return tr.hub_angle;
    case Channel::kHubRate: return tr.hub_rate;
    case Channel::kTipDeflection: return tr.tip_deflection;
    case Channel::kHubTorque: return tr.torque;
  }
  return tr.hub_angle;
}

bool is_closed_loop(ReplayMode mode) {
  if (mode == ReplayMode::kInverseDynamics)
    throw std::invalid_argument("the observer runs in closed or open loop, not in inverse dynamics");
  return mode == ReplayMode::kClosedLoop;
}

// x = [q; v; z] of lane l: q (N), v (N), z (nz).
void get_state(const BatchModel& bm, const BatchState& s, int l, double* x) {
  const int W = bm.W, N = bm.nseg;
  for (int i = 0; i < N; ++i) {
    x[i] = s.q[i * W + l];
    x[N + i] = s.v[i * W + l];
  }
  for (int i = 0; i < bm.layout.nz; ++i) x[2 * N + i] = s.z[i * W + l];
}

void set_state(const BatchModel& bm, BatchState& s, int l, const double* x) {
  const int W = bm.W, N = bm.nseg;
  for (int i = 0; i < N; ++i) {
    s.q[i * W + l] = x[i];
    s.v[i * W + l] = x[N + i];
  }
  for (int i = 0; i < bm.layout.nz; ++i) s.z[i * W + l] = x[2 * N + i];
}


// The model the gain is designed on: the replay model's smooth part (static Coulomb and Stribeck
// friction, backlash, the controller's sensor quantisation, noise and delay left out: a central
// difference across a tanh of width 1e-3 rad/s, a dead zone or a quantum sees a slope the moving arm
// does not have), one controller sample long, with the replay model's own step.
Model make_design_model(const Model& m) {
  ModelSpec s = m.spec;
  if (s.friction.model == "static") s.friction.coulomb = s.friction.stiction = 0.0;
  s.drive.backlash = 0.0;
  for (ChannelSpec* c : {&s.sensors.hub_angle, &s.sensors.hub_rate}) {
    c->resolution = 0.0;
    c->noise = 0.0;
    c->delay = 0;
  }
  s.simulation.substeps = m.substeps;
  s.simulation.duration = m.control_period;
  s.payload_events.clear();
  return make_model(s, "<observer design>", &m);  // the loop closed by m's controller
}

struct Linearisation {
  bool ok = true;
  Eigen::MatrixXd A, C;  // dx_1/dx_0 (nx x nx), dy_0/dx_0 (ny x nx)
};

// A and C at x0 by central differences: lanes x0 +- delta_i e_i run one controller sample (the
// record's input at sample 0 held), x_1 read at sample 1 and y_0 from the trace at sample 0.
Linearisation linearise(const Model& dm, const SampleInputs& in0, const std::vector<Channel>& channels,
                        const Eigen::VectorXd& x0) {
  const int nx = static_cast<int>(x0.size()), ny = static_cast<int>(channels.size()), lanes = 2 * nx;
  const Eigen::VectorXd delta = make_difference_steps(x0);
  Eigen::MatrixXd x1(nx, lanes), y0(ny, lanes);
  Linearisation lin;
  for (int first = 0; first < lanes; first += kMaxLanes) {
    const int W = std::min(kMaxLanes, lanes - first);
    const BatchModel bm = make_batch(std::vector<Model>(W, dm));
    Eigen::VectorXd x(nx);
    SampleInputs in = in0;
    in.at_sample = [&](BatchState& s) {
      if (s.sample != 0) return;
      for (int l = 0; l < W; ++l) {
        const int j = first + l, i = j / 2;  // lane 2i: +delta_i, 2i + 1: -delta_i
        x = x0;
        x[i] += j % 2 == 0 ? delta[i] : -delta[i];
        set_state(bm, s, l, x.data());
      }
    };
    auto observe = [&](const BatchState& s) {
      if (s.sample != 1) return;
      for (int l = 0; l < W; ++l) {
        get_state(bm, s, l, x.data());
        x1.col(first + l) = x;
      }
    };
    const BatchRun run = simulate(bm, observe, &in);
    for (int l = 0; l < W; ++l) {
      lin.ok = lin.ok && run.status[l] == LaneStatus::kOk;
      for (int c = 0; c < ny; ++c) y0(c, first + l) = trace_channel(run.traces[l], channels[c])[0];
    }
  }
  lin.A = calc_central_differences(x1, delta);
  lin.C = calc_central_differences(y0, delta);
  lin.ok = lin.ok && lin.A.allFinite() && lin.C.allFinite();
  return lin;
}

// |P - DARE(P)|_F / |P|_F.
double dare_residual(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q,
                     const Eigen::MatrixXd& R, const Eigen::MatrixXd& P) {
  const Eigen::MatrixXd S = C * P * C.transpose() + R;
  const Eigen::MatrixXd APC = A * P * C.transpose();
  const Eigen::MatrixXd next = A * P * A.transpose() - APC * S.ldlt().solve(APC.transpose()) + Q;
  const double size = P.norm();
  return size > 0 ? (P - next).norm() / size : (next.norm() == 0 ? 0.0 : INFINITY);
}

}  // namespace

Eigen::VectorXd make_difference_steps(const Eigen::VectorXd& x0) {
  Eigen::VectorXd delta(x0.size());
  for (Eigen::Index i = 0; i < x0.size(); ++i) delta[i] = 1e-6 * std::max(1.0, std::abs(x0[i]));  // state units
  return delta;
}

Eigen::MatrixXd calc_central_differences(const Eigen::MatrixXd& f, const Eigen::VectorXd& delta) {
  Eigen::MatrixXd d(f.rows(), delta.size());
  for (Eigen::Index i = 0; i < delta.size(); ++i) d.col(i) = (f.col(2 * i) - f.col(2 * i + 1)) / (2.0 * delta[i]);
  return d;
}

std::vector<long> find_measured_samples(const Record& r, double T, long n) {
  std::vector<long> at(n, -1);
  for (std::size_t j = 0; j < r.t.size(); ++j) {
    const double u = (r.t[j] - r.t.front()) / T;
    const long k = std::lround(u);
    if (k >= 0 && k < n && std::abs(u - k) <= 0.25 && at[k] < 0) at[k] = static_cast<long>(j);
  }
  return at;
}

int calc_measurement_period(const std::vector<long>& at) {
  std::vector<long> gaps;
  long last = -1;
  for (long k = 0; k < static_cast<long>(at.size()); ++k)
    if (at[k] >= 0) {
      if (last >= 0) gaps.push_back(k - last);
      last = k;
    }
  if (gaps.empty()) return 1;
  std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
  return static_cast<int>(std::max(1L, gaps[gaps.size() / 2]));
}

Eigen::MatrixXd calc_process_noise(int joints, int nx, double T, double sigma_a, bool continuous) {
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(nx, nx);
  const double s2 = sigma_a * sigma_a;
  for (int i = 0; i < joints; ++i) {
    Q(i, i) = s2 * T * T * T * T / (continuous ? 3.0 : 4.0);
    Q(i, joints + i) = Q(joints + i, i) = s2 * T * T * T / 2.0;
    Q(joints + i, joints + i) = s2 * T * T;
  }
  return Q;
}

void set_measurement_noise(const Record& r, ObserverDesign& d) {
  const int ny = static_cast<int>(d.channels.size());
  d.R = Eigen::MatrixXd::Zero(ny, ny);
  d.noise_std.clear();
  for (int c = 0; c < ny; ++c) {
    const auto& y = r.at(d.channels[c]);
    double mean = 0.0, var = 0.0;
    for (double v : y) mean += v;
    mean /= y.size();
    for (double v : y) var += (v - mean) * (v - mean);
    var /= y.size();
    d.R(c, c) = std::max({calc_white_noise_variance(y), 1e-12 * var, 1e-300});
    d.noise_std.push_back(std::sqrt(d.R(c, c)));
  }
}

void design_steady_gain(const Eigen::MatrixXd& A1, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q1, ObserverDesign& d) {
  const Eigen::Index nx = A1.rows();
  // Over one measurement period m: A^m, Q_m = sum_{j<m} A^j Q A^jT.
  d.A = Eigen::MatrixXd::Identity(nx, nx);
  d.Q = Eigen::MatrixXd::Zero(nx, nx);
  for (int j = 0; j < d.period; ++j) {
    d.Q += d.A * Q1 * d.A.transpose();
    d.A = A1 * d.A;
  }
  d.C = C;
  const RiccatiSolution dare = solve_filter_dare(d.A, d.C, d.Q, d.R);
  d.doublings = dare.iterations;
  d.ok = false;
  if (!dare.ok) {
    d.message = "the Riccati equation of the observer's gain has no solution (residual " +
                std::to_string(dare.residual) + " after " + std::to_string(dare.iterations) + " doublings)";
    return;
  }
  d.P = dare.P;
  const Eigen::MatrixXd S = d.C * d.P * d.C.transpose() + d.R;
  d.L = S.ldlt().solve(d.C * d.P).transpose();  // P C^T S^-1 (S and P symmetric)
  const Eigen::MatrixXd E = (Eigen::MatrixXd::Identity(nx, nx) - d.L * d.C) * d.A;
  d.pole_radius = E.eigenvalues().cwiseAbs().maxCoeff();
  d.ok = d.L.allFinite() && d.pole_radius < 1.0;
  if (!d.ok) d.message = "the observer's linearised error dynamics do not decay";
}

std::vector<std::string> observer_channels(const Model& m, const Record& r, ReplayMode mode) {
  const bool closed = is_closed_loop(mode);
  std::vector<std::string> out = {"hub_angle"};
  for (const char* c : {"hub_rate", "tip_deflection"})
    if (r.has(c)) out.push_back(c);
  const DriveLayout layout = make_drive_layout(m.spec);
  if (closed && r.has("hub_torque") && (layout.pressure >= 0 || layout.shaft >= 0)) out.push_back("hub_torque");
  return out;
}

double calc_white_noise_variance(const std::vector<double>& y) {
  if (y.size() < 3) return 0.0;
  double sum = 0.0;
  for (std::size_t k = 1; k + 1 < y.size(); ++k) {
    const double d = y[k + 1] - 2.0 * y[k] + y[k - 1];
    sum += d * d;
  }
  return sum / (static_cast<double>(y.size() - 2) * 6.0);
}

RiccatiSolution solve_filter_dare(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C, const Eigen::MatrixXd& Q,
                                  const Eigen::MatrixXd& R) {
  const Eigen::Index n = A.rows();
  RiccatiSolution out;
  const Eigen::LDLT<Eigen::MatrixXd> rl(R);
  if (rl.info() != Eigen::Success || !rl.isPositive()) return out;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  // The filter DARE is the control DARE of (A^T, C^T): X = A_0^T X (I + G_0 X)^-1 A_0 + H_0.
  Eigen::MatrixXd a = A.transpose(), g = C.transpose() * rl.solve(C), h = Q;
  bool converged = false;
  for (int it = 1; it <= 100 && !converged; ++it) {
    const Eigen::PartialPivLU<Eigen::MatrixXd> w(I + g * h);
    const Eigen::MatrixXd wa = w.solve(a), wg = w.solve(g);
    Eigen::MatrixXd h1 = h + a.transpose() * h * wa;
    Eigen::MatrixXd g1 = g + a * wg * a.transpose();
    a = a * wa;
    h1 = 0.5 * (h1 + h1.transpose()).eval();
    g1 = 0.5 * (g1 + g1.transpose()).eval();
    out.iterations = it;
    if (!h1.allFinite() || !g1.allFinite() || !a.allFinite()) return out;
    converged = (h1 - h).norm() <= 1e-13 * h1.norm();
    h = std::move(h1);
    g = std::move(g1);
  }
  out.P = h;
  out.residual = dare_residual(A, C, Q, R, h);
  out.ok = converged && out.residual <= 1e-8;
  return out;
}

ObserverDesign design_observer(const Model& model, const Record& r, ReplayMode mode, const ObserverOptions& options) {
  const bool closed = is_closed_loop(mode);
  if (!(options.process_noise > 0.0) || !std::isfinite(options.process_noise))
    throw std::invalid_argument("the observer's process noise must be a positive number (rad/s^2)");
  ObserverDesign d;
  d.process_noise = options.process_noise;
  d.channels = observer_channels(model, r, mode);
  std::vector<Channel> channels;
  for (const auto& c : d.channels) channels.push_back(channel_of(c));
  const Model m = make_replay_model(model, r);
  const double T = m.control_period;
  const long ns = std::lround(m.duration / T) + 1;
  // R: the white-noise variance of each channel, at least 1e-12 of its variance (a noise-free record).
  set_measurement_noise(r, d);
  // Linearisation about the model's own initial state (the arm at rest) with the record's first input.
  const Model dm = make_design_model(m);
  const BatchModel b1 = make_batch(std::span<const Model>(&dm, 1));
  const int nx = 2 * b1.nseg + b1.layout.nz;
  Eigen::VectorXd x0(nx);
  get_state(b1, make_state(b1), 0, x0.data());
  const Linearisation lin = linearise(dm, make_record_inputs(r, closed, T, 1), channels, x0);
  if (!lin.ok) {
    d.message = "the model failed numerically in its linearisation";
    return d;
  }
  d.period = calc_measurement_period(find_measured_samples(r, T, ns));
  design_steady_gain(lin.A, lin.C, calc_process_noise(b1.nseg, nx, T, options.process_noise), d);
  return d;
}

ObserverRun run_observer(std::span<const Model> models, const Record& r, ReplayMode mode, int k_ahead,
                         const ObserverOptions& options) {
  const bool closed = is_closed_loop(mode);
  if (k_ahead < 0) throw std::invalid_argument("run_observer: k_ahead must be >= 0");
  const int M = static_cast<int>(models.size());
  ObserverRun out;
  std::vector<Model> lanes;
  for (const auto& m : models) {
    lanes.push_back(make_replay_model(m, r));
    out.design.push_back(design_observer(m, r, mode, options));
  }
  if (k_ahead > 0)
    for (int l = 0; l < M; ++l) lanes.push_back(lanes[l]);  // lanes M..2M-1: the k-step predictions
  const BatchModel bm = make_batch(lanes);
  const double T = bm.control_period;
  const long ns = std::lround(bm.duration / T) + 1;
  const int nx = 2 * bm.nseg + bm.layout.nz, W = bm.W;
  out.nx = nx;
  if (!options.initial_state.empty() && static_cast<int>(options.initial_state.size()) != nx)
    throw std::invalid_argument("run_observer: the initial state needs " + std::to_string(nx) + " values");

  SampleInputs in = make_record_inputs(r, closed, T, ns);
  const std::vector<long> measured = find_measured_samples(r, T, ns);
  const std::vector<std::string>& names = out.design[0].channels;  // lanes share a shape, so their channels
  std::vector<Channel> channels;
  std::vector<const std::vector<double>*> column;
  bool need_tip = false, need_torque = false;
  for (const auto& c : names) {
    channels.push_back(channel_of(c));
    column.push_back(&r.at(c));
    need_tip |= channels.back() == Channel::kTipDeflection;
    need_torque |= channels.back() == Channel::kHubTorque;
  }
  const int ny = static_cast<int>(channels.size());
  // The hub angle and rate as each lane's model logs them, brought back on time: a column logged as read is
  // d + L controller samples late (kernel/sensors.hpp unlog_channel), and the observer compares it with the
  // state now. Empty: the record's own column (on time).
  std::vector<std::vector<std::vector<double>>> on_time(M, std::vector<std::vector<double>>(ny));
  for (int l = 0; l < M; ++l)
    for (int c = 0; c < ny; ++c) {
      if (channels[c] != Channel::kHubAngle && channels[c] != Channel::kHubRate) continue;
      const LoopChannelSpec& ch =
          loop_channel_spec(models[l].spec.sensors, channels[c] == Channel::kHubAngle ? kLoopHubAngle : kLoopHubRate);
      const int late = (is_logged_on_time(ch) ? 0 : ch.delay) + ch.logged_delay;
      if (late == 0) continue;
      for (double t : r.t) on_time[l][c].push_back(interpolate(r.t, *column[c], t + late * T));
    }
  out.state.assign(M, std::vector<double>(static_cast<std::size_t>(ns) * nx));
  // Scratch for the hook, made once: nothing is allocated while the batch steps.
  Workspace ws = make_workspace(bm);
  std::vector<double> defl(W), tip_angle(W), torque(W), x(nx), e(ny);
  in.at_sample = [&](BatchState& s) {
    const long k = s.sample;
    if (k == 0 && !options.initial_state.empty())
      for (int l = 0; l < M; ++l) set_state(bm, s, l, options.initial_state.data());
    // A k-step prediction starts from x(k|k-1) and the observer's controller states.
    if (k_ahead > 0 && k % k_ahead == 0)
      for (int l = 0; l < M; ++l) copy_lane(bm, s, l, M + l);
    const long j = measured[k];
    if (j >= 0) {
      if (need_tip) compute_tip(bm, s.q.data(), defl.data(), tip_angle.data(), ws);
      if (need_torque) compute_actuator_torque(bm, s.q.data(), s.v.data(), s.z.data(), s.tau.data(), torque.data());
      for (int l = 0; l < M; ++l) {
        const ObserverDesign& d = out.design[l];
        if (!d.ok || s.status[l] != LaneStatus::kOk) continue;
        for (int c = 0; c < ny; ++c) {
          double yhat = 0.0;
          switch (channels[c]) {
            case Channel::kHubAngle: yhat = s.q[l]; break;
            case Channel::kHubRate: yhat = s.v[l]; break;
            case Channel::kTipDeflection: yhat = defl[l]; break;
            case Channel::kHubTorque: yhat = torque[l]; break;
          }
          e[c] = (on_time[l][c].empty() ? (*column[c])[j] : on_time[l][c][j]) - yhat;  // innovation
        }
        get_state(bm, s, l, x.data());
        for (int i = 0; i < nx; ++i)
          for (int c = 0; c < ny; ++c) x[i] += d.L(i, c) * e[c];
        set_state(bm, s, l, x.data());
      }
    }
    for (int l = 0; l < M; ++l) get_state(bm, s, l, out.state[l].data() + k * nx);
  };
  BatchRun run = simulate(bm, nullptr, &in);
  for (int l = 0; l < M; ++l) {
    out.estimate.push_back(std::move(run.traces[l]));
    out.estimate_status.push_back(run.status[l]);
    if (k_ahead > 0) {
      out.k_step.push_back(std::move(run.traces[M + l]));
      out.k_step_status.push_back(run.status[M + l]);
    }
  }
  return out;
}

}  // namespace ff
