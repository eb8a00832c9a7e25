#include "kernel/dynamics.hpp"

#include <algorithm>
#include <cmath>

#include "common/isa.hpp"
#include "kernel/drive.hpp"
#include "kernel/fastmath.hpp"
#include "kernel/friction.hpp"

namespace ff {

// Planar spatial vectors in body coordinates: motion (w, vx, vy), force (n, fx, fy).
// Body i's frame sits on joint i with x along the segment; joint i+1 is at (L_i, 0).
// Parent-to-child transform (Featherstone's plnr(q, [L_parent, 0])):
//   X = [[1, 0, 0], [s L, c, s], [c L, -s, c]],  c = cos q, s = sin q.

double calc_hub_friction(const BatchModel& bm, int l, double q, double w) {
  return calc_friction_torque(at_angle(bm.friction[l], q), w);
}

double calc_hub_friction_damping(const BatchModel& bm, int l, double q, double w) {
  return calc_friction_damping(at_angle(bm.friction[l], q), w);
}

static void compute_joint_torques_kernel(const BatchModel& bm, const double* q, const double* v,
                                         const double* tau_hub, double* tj) {
  const int W = bm.W, N = bm.nseg;
  const double* k = bm.joint_k.data();
  const double* c = bm.joint_c.data();
  const double* k3 = bm.joint_k3.data();
  std::copy(tau_hub, tau_hub + W, tj);
  // Spring-damper torque on the child of each beam joint.
  for (int i = 1; i < N; ++i) {
    const int o = i * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double x = q[o + l];
      tj[o + l] = -(k[o + l] + k3[o + l] * x * x) * x - c[o + l] * v[o + l];
    }
  }
}
FF_ISA_DISPATCH(void, compute_joint_torques,
                (const BatchModel& bm, const double* q, const double* v, const double* tau_hub, double* tj),
                (bm, q, v, tau_hub, tj))

namespace {
// s[j] = sin x[j], c[j] = cos x[j] for j < n, in one flat loop: the polynomials of different
// entries are independent, so their latency chains overlap.
void compute_sincos(int n, const double* x, double* s, double* c) {
#pragma omp simd
  for (int j = 0; j < n; ++j) calc_sincos(x[j], s[j], c[j]);
}
}  // namespace

static void compute_forward_dynamics_kernel(const BatchModel& bm, const BodyTable& body, const double* q,
                                            const double* v, const double* tau, const double* arm, double* qdd,
                                            Workspace& ws) {
  const int W = bm.W, N = bm.nseg;
  // Bodies 0..N-2 (the parents pass 2 projects onto) by offset into the table; the tip by its row.
  const double* bmass = body.mass;
  const double* bfirst = body.first;
  const double* binert = body.inertia;
  const BodyRow tip = body.tip;
  const double* len = bm.seg_length.data();
  double *cq = ws.cq.data(), *sq = ws.sq.data(), *vw = ws.vw.data(), *vx = ws.vx.data(), *vy = ws.vy.data();
  double *cy = ws.cy.data(), *cz = ws.cz.data();
  double *i00 = ws.i00.data(), *i01 = ws.i01.data(), *i02 = ws.i02.data();
  double *i11 = ws.i11.data(), *i12 = ws.i12.data(), *i22 = ws.i22.data();
  double *p0 = ws.p0.data(), *p1 = ws.p1.data(), *p2 = ws.p2.data();
  double *d = ws.d.data(), *u = ws.u.data(), *a0 = ws.a0.data(), *a1 = ws.a1.data(), *a2 = ws.a2.data();

  // Joint transforms of bodies 1..N-1 (body 0's rotation never enters: fixed hub axis, no gravity).
  compute_sincos((N - 1) * W, q + W, sq + W, cq + W);

  // Pass 1, root to tip: velocities, velocity-product accelerations and rigid-body bias forces.
  // The rigid inertias I_i = [[J, 0, h], [0, m, 0], [h, 0, m]] are read from the body table in pass 2.
  auto pass1 = [=](int o, int l, const BodyRow& b, double w, double x, double y) {
    vw[o + l] = w;
    vx[o + l] = x;
    vy[o + l] = y;
    // c_i = crm(v_i) S qd_i = (0, vy qd, -vx qd)
    cy[o + l] = y * v[o + l];
    cz[o + l] = -x * v[o + l];
    // p_i = crf(v_i) I_i v_i
    const double h = b.first[l], m = b.mass[l];
    const double fx = m * x, fy = h * w + m * y;
    p0[o + l] = -y * fx + x * fy;
    p1[o + l] = -w * fy;
    p2[o + l] = w * fx;
  };
  const BodyRow b0 = body.row(0);
#pragma omp simd
  for (int l = 0; l < W; ++l) pass1(0, l, b0, v[l], 0.0, 0.0);
  for (int i = 1; i < N; ++i) {
    const int o = i * W, op = (i - 1) * W;
    const BodyRow b = body.row(i);
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double c = cq[o + l], s = sq[o + l];
      const double lp = len[op + l], wp = vw[op + l], xp = vx[op + l], yp = vy[op + l];
      pass1(o, l, b, wp + v[o + l], s * lp * wp + c * xp + s * yp, c * lp * wp - s * xp + c * yp);
    }
  }

  // Pass 2, tip to root: articulated inertias IA (symmetric, i00..i22) and bias forces pA, projected
  // across each revolute joint. Body i's IA = I_i + X^T Ia X of its child, written when the child is done;
  // the tip's IA is its rigid inertia.
  auto project = [=](int o, int op, int l, double U0, double U1, double U2, double I11, double I12, double I22) {
    // U = IA S, d = S^T U + armature, u = tau - S^T pA
    const double di = U0 + arm[o + l];
    const double ui = tau[o + l] - p0[o + l];
    d[o + l] = di;
    u[o + l] = ui;
    // Ia = IA - U U^T / d ;  pa = pA + Ia c + U u / d
    const double r = 1.0 / di;
    const double a00 = U0 - U0 * U0 * r, a01 = U1 - U0 * U1 * r, a02 = U2 - U0 * U2 * r;
    const double a11 = I11 - U1 * U1 * r, a12 = I12 - U1 * U2 * r, a22 = I22 - U2 * U2 * r;
    const double ccy = cy[o + l], ccz = cz[o + l], ur = ui * r;
    const double pa0 = p0[o + l] + a01 * ccy + a02 * ccz + U0 * ur;
    const double pa1 = p1[o + l] + a11 * ccy + a12 * ccz + U1 * ur;
    const double pa2 = p2[o + l] + a12 * ccy + a22 * ccz + U2 * ur;
    // Parent: IA = I + X^T Ia X, pA = p + X^T pa
    const double c = cq[o + l], s = sq[o + l], lp = len[op + l], sl = s * lp, cl = c * lp;
    const double P0 = a00 + a01 * sl + a02 * cl, P1 = a01 + a11 * sl + a12 * cl, P2 = a02 + a12 * sl + a22 * cl;
    const double Q0 = a01 * c - a02 * s, Q1 = a11 * c - a12 * s, Q2 = a12 * c - a22 * s;
    const double R0 = a01 * s + a02 * c, R1 = a11 * s + a12 * c, R2 = a12 * s + a22 * c;
    const double J = binert[op + l], h = bfirst[op + l], m = bmass[op + l];
    i00[op + l] = J + (P0 + sl * P1 + cl * P2);
    i01[op + l] = 0.0 + (Q0 + sl * Q1 + cl * Q2);
    i02[op + l] = h + (R0 + sl * R1 + cl * R2);
    i11[op + l] = m + (c * Q1 - s * Q2);
    i12[op + l] = 0.0 + (c * R1 - s * R2);
    i22[op + l] = m + (s * R1 + c * R2);
    p0[op + l] += pa0 + sl * pa1 + cl * pa2;
    p1[op + l] += c * pa1 - s * pa2;
    p2[op + l] += s * pa1 + c * pa2;
  };
  if (N == 1) {
#pragma omp simd
    for (int l = 0; l < W; ++l) i00[l] = tip.inertia[l];
  } else {
    const int o = (N - 1) * W, op = (N - 2) * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double J = tip.inertia[l], h = tip.first[l], m = tip.mass[l];
      i00[o + l] = J;  // U of the tip, for pass 3
      i01[o + l] = 0.0;
      i02[o + l] = h;
      project(o, op, l, J, 0.0, h, m, 0.0, m);
    }
  }
  for (int i = N - 2; i >= 1; --i) {
    const int o = i * W, op = (i - 1) * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) project(o, op, l, i00[o + l], i01[o + l], i02[o + l], i11[o + l], i12[o + l], i22[o + l]);
  }

  // Pass 3, root to tip: accelerations a_i = X a_parent + c_i, qdd_i = (u_i - U_i^T a_i) / d_i.
  // The hub: fixed base, no gravity (horizontal plane), so a = S qdd_0.
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    const double qa = (tau[l] - p0[l]) / (i00[l] + arm[l]);
    qdd[l] = qa;
    a0[l] = qa;
    a1[l] = 0.0;
    a2[l] = 0.0;
  }
  for (int i = 1; i < N; ++i) {
    const int o = i * W, op = (i - 1) * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double c = cq[o + l], s = sq[o + l], lp = len[op + l];
      const double x0 = a0[op + l], x1 = a1[op + l], x2 = a2[op + l];
      const double b1 = s * lp * x0 + c * x1 + s * x2 + cy[o + l];
      const double b2 = c * lp * x0 - s * x1 + c * x2 + cz[o + l];
      const double qa = (u[o + l] - (i00[o + l] * x0 + i01[o + l] * b1 + i02[o + l] * b2)) / d[o + l];
      qdd[o + l] = qa;
      a0[o + l] = x0 + qa;
      a1[o + l] = b1;
      a2[o + l] = b2;
    }
  }
}
FF_ISA_DISPATCH(void, compute_forward_dynamics,
                (const BatchModel& bm, const BodyTable& body, const double* q, const double* v, const double* tau,
                 const double* arm, double* qdd, Workspace& ws),
                (bm, body, q, v, tau, arm, qdd, ws))

void compute_forward_dynamics(const BatchModel& bm, const double* q, const double* v, const double* tau,
                              const double* arm, double* qdd, Workspace& ws) {
  compute_forward_dynamics(bm, make_body_table(bm), q, v, tau, arm, qdd, ws);
}

void compute_acceleration(const BatchModel& bm, const BodyTable& body, const double* q, const double* v,
                          const double* z, const double* tau_cmd, double* qdd, double* zdot, Workspace& ws) {
  compute_hub_drive(bm, q, v, z, tau_cmd, ws.tau_hub.data(), zdot);
  compute_joint_torques(bm, q, v, ws.tau_hub.data(), ws.tau_joint.data());
  compute_forward_dynamics(bm, body, q, v, ws.tau_joint.data(), ws.armature.data(), qdd, ws);
}

void compute_acceleration(const BatchModel& bm, const double* q, const double* v, const double* z,
                          const double* tau_cmd, double* qdd, double* zdot, Workspace& ws) {
  compute_acceleration(bm, make_body_table(bm), q, v, z, tau_cmd, qdd, zdot, ws);
}

static void compute_tip_kernel(const BatchModel& bm, const double* q, double* deflection, double* angle,
                               Workspace& ws) {
  const int W = bm.W;
  // Running angle of each segment relative to the hub, as cos/sin by angle addition.
  double* cphi = ws.a0.data();
  double* sphi = ws.a1.data();
  double* along = ws.a2.data();
  const double* len = bm.seg_length.data();
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    cphi[l] = 1.0;
    sphi[l] = 0.0;
    deflection[l] = 0.0;
    along[l] = len[l];
  }
  double* sq = ws.sq.data();
  double* cq = ws.cq.data();
  compute_sincos((bm.nseg - 1) * W, q + W, sq + W, cq + W);
  for (int i = 1; i < bm.nseg; ++i) {
    const int o = i * W;
#pragma omp simd
    for (int l = 0; l < W; ++l) {
      const double s = sq[o + l], c = cq[o + l];
      const double cn = cphi[l] * c - sphi[l] * s, sn = sphi[l] * c + cphi[l] * s;
      cphi[l] = cn;
      sphi[l] = sn;
      deflection[l] += len[o + l] * sn;
      along[l] += len[o + l] * cn;
    }
  }
  // Tip angle: hub angle plus the direction of the tip seen from the hub (fastmath.hpp atan2), rad.
#pragma omp simd
  for (int l = 0; l < W; ++l) angle[l] = q[l] + calc_atan2(deflection[l], along[l]);
}
FF_ISA_DISPATCH(void, compute_tip,
                (const BatchModel& bm, const double* q, double* deflection, double* angle, Workspace& ws),
                (bm, q, deflection, angle, ws))

void compute_tip_acceleration(const BatchModel& bm, const double* q, const double* v, const double* qdd,
                              double* accel) {
  const int W = bm.W;
  for (int l = 0; l < W; ++l) {
    double phi = 0.0, rate = 0.0, acc = 0.0, y = 0.0;  // phi_i and its derivatives, rad, rad/s, rad/s^2
    for (int i = 1; i < bm.nseg; ++i) {
      const int o = i * W + l;
      phi += q[o];
      rate += v[o];
      acc += qdd[o];
      y += bm.seg_length[o] * (std::cos(phi) * acc - std::sin(phi) * rate * rate);
    }
    accel[l] = y;
  }
}

TipKinematics calc_tip(const BatchModel& bm, const double* q, int lane) {
  const int W = bm.W;
  double phi = 0.0, defl = 0.0, along = 0.0;
  for (int i = 0; i < bm.nseg; ++i) {
    if (i > 0) phi += q[i * W + lane];  // segment angle relative to the hub
    const double li = bm.seg_length[i * W + lane];
    defl += li * std::sin(phi);
    along += li * std::cos(phi);
  }
  return {defl, along, q[lane] + std::atan2(defl, along)};
}

double calc_kinetic_energy(const BatchModel& bm, const double* q, const double* v, int lane) {
  return calc_kinetic_energy(bm, make_body_table(bm), q, v, lane);
}

double calc_kinetic_energy(const BatchModel& bm, const BodyTable& body, const double* q, const double* v, int lane) {
  const int W = bm.W;
  double w = 0.0, x = 0.0, y = 0.0, T = 0.0;
  for (int i = 0; i < bm.nseg; ++i) {
    const int o = i * W + lane;
    const double c = std::cos(q[o]), s = std::sin(q[o]);
    if (i == 0) {
      w = v[o];
    } else {
      const double lp = bm.seg_length[o - W];
      const double xn = s * lp * w + c * x + s * y, yn = c * lp * w - s * x + c * y;
      w += v[o];
      x = xn;
      y = yn;
    }
    // 1/2 v^T I v with I = [[J, 0, h], [0, m, 0], [h, 0, m]]
    const BodyRow b = body.row(i);
    T += 0.5 * (b.inertia[lane] * w * w + 2.0 * b.first[lane] * w * y + b.mass[lane] * (x * x + y * y));
  }
  return T;
}

double calc_spring_energy(const BatchModel& bm, const double* q, int lane) {
  double V = 0.0;
  for (int i = 1; i < bm.nseg; ++i) {
    const int o = i * bm.W + lane;
    const double x2 = q[o] * q[o];
    V += 0.5 * bm.joint_k[o] * x2 + 0.25 * bm.joint_k3[o] * x2 * x2;
  }
  return V;
}

}  // namespace ff
