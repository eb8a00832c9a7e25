#include "validate/replay.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "kernel/batch.hpp"
#include "kernel/dynamics.hpp"
#include "kernel/modes.hpp"
#include "kernel/sensors.hpp"
#include "kernel/simulate.hpp"
#include "validate/observer.hpp"

namespace ff {

const char* replay_mode_name(ReplayMode m) {
  switch (m) {
    case ReplayMode::kClosedLoop: return "closed-loop";
    case ReplayMode::kOpenLoop: return "open-loop";
    case ReplayMode::kInverseDynamics: return "inverse-dynamics";
  }
  return "?";
}

ReplayMode parse_replay_mode(const std::string& name) {
  for (auto m : {ReplayMode::kClosedLoop, ReplayMode::kOpenLoop, ReplayMode::kInverseDynamics})
    if (name == replay_mode_name(m)) return m;
  throw std::invalid_argument("unknown mode '" + name + "' (closed-loop, open-loop, inverse-dynamics)");
}

std::vector<std::string> replay_inputs(ReplayMode mode) {
  switch (mode) {
    case ReplayMode::kClosedLoop: return {"ref", "hub_angle"};
    case ReplayMode::kOpenLoop: return {"hub_torque", "hub_angle"};
    case ReplayMode::kInverseDynamics: return {"hub_torque", "hub_angle"};
  }
  return {};
}

std::vector<std::string> scored_channels(ReplayMode mode, const Record& r) {
  if (mode == ReplayMode::kInverseDynamics) return {"hub_torque"};
  std::vector<std::string> out = {"hub_angle"};
  for (const char* c : {"tip_deflection", "hub_torque"})
    if (r.has(c) && !(mode == ReplayMode::kOpenLoop && std::string(c) == "hub_torque")) out.push_back(c);
  return out;
}

Fit calc_fit(const std::vector<double>& y, const std::vector<double>& yhat) {
  double mean = 0.0;
  for (double x : y) mean += x;
  mean /= y.size();
  double e2 = 0.0, d2 = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    e2 += (y[k] - yhat[k]) * (y[k] - yhat[k]);
    d2 += (y[k] - mean) * (y[k] - mean);
  }
  Fit f;
  f.rmse = std::sqrt(e2 / y.size());
  f.percent = d2 > 0 ? 100.0 * (1.0 - std::sqrt(e2 / d2)) : (e2 == 0 ? 100.0 : -INFINITY);
  if (!std::isfinite(e2)) f.percent = -INFINITY;
  return f;
}

Model make_replay_model(const Model& m, const Record& r) {
  ModelSpec s = m.spec;
  s.simulation.duration = r.t.back() - r.t.front();
  s.payload_events.clear();
  return make_model(s, "<replay>", &m);  // m's controller: its feed-forward inertia, notch and shaper
}

namespace {

// The measured signal at every controller sample k (t = t0 + k T).
std::vector<double> at_samples(const Record& r, const std::vector<double>& y, double T, long n) {
  std::vector<double> out(n);
  for (long k = 0; k < n; ++k) out[k] = interpolate(r.t, y, r.t.front() + k * T);
  return out;
}

}  // namespace

SampleInputs make_record_inputs(const Record& r, bool closed_loop, double T, long n) {
  SampleInputs in;
  if (!closed_loop) {
    in.torque = at_samples(r, r.at("hub_torque"), T, n);
    return in;
  }
  // The reference and its rate and acceleration from its piecewise cubics (exact for cubic moves, the jump of
  // r'' at a move's knots kept: a feed-forward J r'' sees it as the controller did).
  SmoothSamples ref = sample_piecewise_smooth(r.t, r.at("ref"), r.t.front(), T, n);
  in.ref = std::move(ref.value);
  in.ref_rate = std::move(ref.rate);
  in.ref_accel = std::move(ref.accel);
  return in;
}

namespace {

// Central differences of x (spacing T), one-sided at the ends.
std::vector<double> derivative(const std::vector<double>& x, double T) {
  const std::size_t n = x.size();
  std::vector<double> d(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t a = k > 0 ? k - 1 : 0, b = k + 1 < n ? k + 1 : n - 1;
    d[k] = (x[b] - x[a]) / ((b - a) * T);
  }
  return d;
}

// Simulated channels of one trace at the record's times: the in-loop channels (hub angle and rate) as
// logged (sensors.*.logged: read, what the controller read; true, on time), the output channels (hub
// torque, tip deflection, pressures) as the model's sensors measure them; without noise.
Prediction sample_trace(const Model& m, const Trace& tr, const Record& r, bool ok) {
  Prediction p;
  p.ok = ok;
  std::vector<std::pair<std::string, std::vector<double>>> ch = {
      {"hub_angle", log_loop_channel(m, kLoopHubAngle, tr.hub_angle, false)},
      {"hub_rate", log_loop_channel(m, kLoopHubRate, tr.hub_rate, false)},
      {"tip_deflection", measure_output(m, kOutTipDeflection, tr.tip_deflection, false)},
      {"hub_torque", measure_output(m, kOutHubTorque, tr.torque, false)}};
  for (const auto& [name, x] : tr.extra)
    if (const OutputChannel c = find_output_channel(name); c != kOutputChannels)
      ch.emplace_back(name, measure_output(m, c, x, false));
  // The trace is uniform in time (t_k = k T): each record time's neighbours and weight, once.
  const double T = m.control_period;
  const std::size_t last = tr.t.size() - 1;
  std::vector<std::size_t> at(r.size());
  std::vector<double> w(r.size());
  for (std::size_t i = 0; i < r.size(); ++i) {
    double x = std::max(0.0, (r.t[i] - r.t.front()) / T);
    if (std::abs(x - std::round(x)) < 1e-9) x = std::round(x);  // on a sample: that sample, exactly
    at[i] = std::min(static_cast<std::size_t>(x), last);
    w[i] = at[i] < last ? x - static_cast<double>(at[i]) : 0.0;
  }
  for (const auto& [name, y] : ch) {
    auto& out = p.channels[name];
    out.resize(r.size());
    for (std::size_t i = 0; i < r.size(); ++i)
      out[i] = w[i] > 0.0 ? y[at[i]] + w[i] * (y[at[i] + 1] - y[at[i]]) : y[at[i]];
  }
  return p;
}

// Inverse dynamics on one model: the hub follows the measured angle exactly; the beam (and LuGre
// bristles) move freely under it. With r = M(q) qdd_free (the passive and velocity torques, friction
// included, from the articulated-body algorithm at zero hub torque), the hybrid dynamics
//   M_bb a_b = r_b - M_b0 a_0,   tau_0 = M_00 a_0 + M_0b a_b - r_0
// give the hub torque needed. Hydraulics and drive train are not inverted (the torque at the hub).
Prediction inverse_dynamics(const Model& model, const Record& r) {
  ModelSpec s = model.spec;
  s.hydraulics.enabled = false;
  s.drive.enabled = false;
  s.controller.load_signal = "moment";
  const Model m = make_replay_model(make_model(s, "<inverse>", &model), r);
  const BatchModel bm = make_batch(std::span<const Model>(&m, 1));
  Workspace ws = make_workspace(bm);
  BatchState st = make_state(bm);
  const int n = m.nseg, nz = bm.layout.nz;
  const double T = m.control_period;
  const long ns = std::lround(m.duration / T) + 1;
  // The hub's motion: the logged columns brought back on time (a column logged as read is d samples late).
  const auto theta = unlog_loop_channel(model, kLoopHubAngle, at_samples(r, r.at("hub_angle"), T, ns));
  const auto omega = r.has("hub_rate") ? unlog_loop_channel(model, kLoopHubRate, at_samples(r, r.at("hub_rate"), T, ns))
                                       : derivative(theta, T);
  const auto alpha = derivative(omega, T);
  // State of the free part: beam joints (q_b, v_b) and drive states z; the hub is prescribed.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n), v = Eigen::VectorXd::Zero(n), qdd(n);
  std::vector<double> z(st.z), zdot(nz), zero_tau(1, 0.0);
  q(0) = theta[0];
  v(0) = omega[0];
  // Beam accelerations and the hub torque at (q, v, z) with hub acceleration a0. Buffers are kept
  // across calls: this runs four times per substep of every sample.
  Eigen::MatrixXd M(n, n);
  Eigen::VectorXd rr(n), rhs(std::max(n - 1, 0));
  Eigen::LDLT<Eigen::MatrixXd> beam(std::max(n - 1, 0));
  auto hybrid = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv, const double* zz, double a0,
                    Eigen::VectorXd& acc, double* zd) {
    compute_acceleration(bm, qq.data(), vv.data(), zz, zero_tau.data(), qdd.data(), zd, ws);
    M = calc_mass_matrix(m, qq);
    rr.noalias() = M * qdd;
    acc.resize(n);
    acc(0) = a0;
    if (n > 1) {
      rhs = rr.tail(n - 1) - M.block(1, 0, n - 1, 1) * a0;
      beam.compute(M.bottomRightCorner(n - 1, n - 1));
      acc.tail(n - 1) = beam.solve(rhs);
    }
    return M.row(0).dot(acc) - rr(0);
  };
  Trace tr;
  const int sub = std::max(1, m.substeps);
  const double h = T / sub;
  Eigen::VectorXd a1(n), a2(n), a3(n), a4(n), v1(n), v2(n), v3(n), v4(n), qs(n), vs(n);
  std::vector<double> k1(nz), k2(nz), k3(nz), k4(nz), zs(nz);
  for (long k = 0; k < ns; ++k) {
    q(0) = theta[k];
    v(0) = omega[k];
    tr.t.push_back(k * T);
    tr.torque.push_back(hybrid(q, v, z.data(), alpha[k], a1, zdot.data()));
    tr.hub_angle.push_back(theta[k]);
    tr.hub_rate.push_back(omega[k]);
    double defl = 0.0, tip = 0.0;
    compute_tip(bm, q.data(), &defl, &tip, ws);
    tr.tip_deflection.push_back(defl);
    if (k + 1 == ns) break;
    // RK4 on the free part over the sample, the hub's acceleration linear in between.
    for (int j = 0; j < sub; ++j) {
      const double u0 = static_cast<double>(j) / sub, u1 = (j + 0.5) / sub, u2 = (j + 1.0) / sub;
      auto a_at = [&](double u) { return alpha[k] + u * (alpha[k + 1] - alpha[k]); };
      // One stage at (q + c dq, v + c dv, z + c dz); the first (c = 0) at the state itself.
      auto stage = [&](const Eigen::VectorXd* dq, const Eigen::VectorXd* dv, const std::vector<double>* dz, double c,
                       double u, Eigen::VectorXd& acc, std::vector<double>& kz, Eigen::VectorXd& qv) {
        qs = q;
        vs = v;
        for (int i = 0; i < nz; ++i) zs[i] = z[i];
        if (dq) {
          qs += c * *dq;
          vs += c * *dv;
          for (int i = 0; i < nz; ++i) zs[i] += c * (*dz)[i];
        }
        hybrid(qs, vs, zs.data(), a_at(u), acc, kz.data());
        qv = vs;
      };
      stage(nullptr, nullptr, nullptr, 0.0, u0, a1, k1, v1);
      stage(&v1, &a1, &k1, 0.5 * h, u1, a2, k2, v2);
      stage(&v2, &a2, &k2, 0.5 * h, u1, a3, k3, v3);
      stage(&v3, &a3, &k3, h, u2, a4, k4, v4);
      q += h / 6.0 * (v1 + 2.0 * v2 + 2.0 * v3 + v4);
      v += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
      for (int i = 0; i < nz; ++i) z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
  }
  Prediction p;
  const std::vector<double> torque = measure_output(model, kOutHubTorque, tr.torque, false);
  for (double t : r.t) p.channels["hub_torque"].push_back(interpolate(tr.t, torque, t - r.t.front()));
  for (double x : p.channels["hub_torque"]) p.ok = p.ok && std::isfinite(x);
  return p;
}

}  // namespace

std::vector<Prediction> replay(std::span<const Model> models, const Record& r, ReplayMode mode, int k_ahead) {
  return replay(models, r, mode, k_ahead, ObserverOptions{});
}

std::vector<Prediction> replay(std::span<const Model> models, const Record& r, ReplayMode mode, int k_ahead,
                               const ObserverOptions& observer) {
  if (mode == ReplayMode::kInverseDynamics) {
    std::vector<Prediction> out(models.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (std::size_t i = 0; i < models.size(); ++i) out[i] = inverse_dynamics(models[i], r);
    return out;
  }
  if (k_ahead > 0) {  // k-step: restarts from the observer's estimate (validate/observer.hpp)
    const ObserverRun o = run_observer(models, r, mode, k_ahead, observer);
    std::vector<Prediction> out;
    for (std::size_t l = 0; l < models.size(); ++l) out.push_back(sample_trace(models[l], o.k_step[l], r, o.k_step_ok(l)));
    return out;
  }
  std::vector<Model> lanes;
  for (const auto& m : models) lanes.push_back(make_replay_model(m, r));
  const BatchModel bm = make_batch(lanes);
  const double T = bm.control_period;
  const long ns = std::lround(bm.duration / T) + 1;
  const SampleInputs in = make_record_inputs(r, mode == ReplayMode::kClosedLoop, T, ns);
  const BatchRun run = simulate(bm, nullptr, &in);
  std::vector<Prediction> out;
  for (int l = 0; l < bm.W; ++l) out.push_back(sample_trace(lanes[l], run.traces[l], r, run.status[l] == LaneStatus::kOk));
  return out;
}

}  // namespace ff
