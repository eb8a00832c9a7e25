#include "multibody/lanes.hpp"

#include <stdexcept>
#include <string>

#include "kernel/fastmath.hpp"

namespace ff {

namespace {

#define FF_INLINE [[gnu::always_inline]] inline

// Small dense helpers on plain arrays, inlined into the lane loops: 3-vectors, 3x3 row-major.
FF_INLINE void cross3(const double* a, const double* b, double* o) {
  o[0] = a[1] * b[2] - a[2] * b[1];
  o[1] = a[2] * b[0] - a[0] * b[2];
  o[2] = a[0] * b[1] - a[1] * b[0];
}
FF_INLINE double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
FF_INLINE void mul3(const double* M, const double* x, double* o) {  // o = M x
  for (int r = 0; r < 3; ++r) o[r] = M[3 * r] * x[0] + M[3 * r + 1] * x[1] + M[3 * r + 2] * x[2];
}
FF_INLINE void mul3t(const double* M, const double* x, double* o) {  // o = M^T x
  for (int c = 0; c < 3; ++c) o[c] = M[c] * x[0] + M[3 + c] * x[1] + M[6 + c] * x[2];
}
FF_INLINE void matmul3(const double* A, const double* B, double* o) {  // o = A B
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) o[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
}
// o = E^T M E (a 3x3 block carried from body to parent coordinates).
FF_INLINE void congruence3(const double* E, const double* M, double* o) {
  double ME[9];
  matmul3(M, E, ME);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) o[3 * r + c] = E[r] * ME[c] + E[3 + r] * ME[3 + c] + E[6 + r] * ME[6 + c];
}
// Symmetric 3x3 packed (xx, xy, xz, yy, yz, zz) to and from full.
FF_INLINE void unpack_sym(const double* p, double* M) {
  M[0] = p[0], M[1] = p[1], M[2] = p[2];
  M[3] = p[1], M[4] = p[3], M[5] = p[4];
  M[6] = p[2], M[7] = p[4], M[8] = p[5];
}

// Lane-innermost views: component k of one body's K-vector at p[k * W + l].
struct LaneBlock {
  double* p;
  int W;
  FF_INLINE double& operator()(int k, int l) const { return p[k * W + l]; }
};
struct ConstLaneBlock {
  const double* p;
  int W;
  ConstLaneBlock(const double* p_, int W_) : p(p_), W(W_) {}
  ConstLaneBlock(const LaneBlock& b) : p(b.p), W(b.W) {}  // NOLINT: a read-only view of a block
  FF_INLINE double operator()(int k, int l) const { return p[k * W + l]; }
};

FF_INLINE LaneBlock block(std::vector<double>& v, int i, int K, int W) {
  return {v.data() + static_cast<std::size_t>(i) * K * W, W};
}
FF_INLINE ConstLaneBlock block(const std::vector<double>& v, int i, int K, int W) {
  return {v.data() + static_cast<std::size_t>(i) * K * W, W};
}

// Pass 1 of the ABA for body i, root to tip, in every lane: the joint transform Xup = X_J(q) X_tree,
// the velocity v = Xup v_parent + S qd, c = v × S qd, and the rigid body's inertia and bias force
// p = v ×* I v as the start of the articulated quantities (RBDA Table 7.1, first loop).
template <JointType J, bool kRoot>
void aba_pass1(const TreeLanes& tl, int i, const double* q, const double* qd, TreeLanesWorkspace& ws) {
  const int W = tl.W, p = tl.parent[i], j = tl.dof[i];
  const ConstLaneBlock ax = block(tl.axis, i, 3, W), Xt = block(tl.X_tree, i, 12, W), In = block(tl.inertia, i, 10, W);
  const LaneBlock Xup = block(ws.Xup, i, 12, W), v = block(ws.v, i, 6, W), c = block(ws.c, i, 6, W);
  const LaneBlock IA = block(ws.IA, i, 21, W), pA = block(ws.pA, i, 6, W);
  const ConstLaneBlock vp = block(ws.v, p < 0 ? 0 : p, 6, W);
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    double Et[9], rt[3], a[3], E[9], r[3];
    for (int k = 0; k < 9; ++k) Et[k] = Xt(k, l);
    for (int k = 0; k < 3; ++k) rt[k] = Xt(9 + k, l), a[k] = ax(k, l);
    double qj = 0.0, qdj = 0.0;
    if constexpr (J != JointType::kFixed) qj = q[j * W + l], qdj = qd[j * W + l];
    // Joint transform. Revolute: E_J = R(a, q)^T = c 1 - s [a]× + (1 - c) a a^T (Rodrigues), r_J = 0;
    // prismatic: E_J = 1, r_J = a q. Composition: E = E_J E_tree, r = r_tree + E_tree^T r_J.
    if constexpr (J == JointType::kRevolute) {
      double s, co;
      calc_sincos(qj, s, co);
      const double t = 1.0 - co;
      const double EJ[9] = {co + t * a[0] * a[0],  s * a[2] + t * a[0] * a[1], -s * a[1] + t * a[0] * a[2],
                            -s * a[2] + t * a[1] * a[0], co + t * a[1] * a[1], s * a[0] + t * a[1] * a[2],
                            s * a[1] + t * a[2] * a[0], -s * a[0] + t * a[2] * a[1], co + t * a[2] * a[2]};
      matmul3(EJ, Et, E);
      for (int k = 0; k < 3; ++k) r[k] = rt[k];
    } else if constexpr (J == JointType::kPrismatic) {
      const double rJ[3] = {a[0] * qj, a[1] * qj, a[2] * qj};
      double d[3];
      mul3t(Et, rJ, d);
      for (int k = 0; k < 9; ++k) E[k] = Et[k];
      for (int k = 0; k < 3; ++k) r[k] = rt[k] + d[k];
    } else {
      for (int k = 0; k < 9; ++k) E[k] = Et[k];
      for (int k = 0; k < 3; ++k) r[k] = rt[k];
    }
    for (int k = 0; k < 9; ++k) Xup(k, l) = E[k];
    for (int k = 0; k < 3; ++k) Xup(9 + k, l) = r[k];
    // v = Xup v_parent + S qd: [E w; E (v - r × w)] (the base is at rest).
    double w[3] = {0.0, 0.0, 0.0}, vl[3] = {0.0, 0.0, 0.0};
    if constexpr (!kRoot) {
      const double wp[3] = {vp(0, l), vp(1, l), vp(2, l)};
      double rw[3], vr[3];
      cross3(r, wp, rw);
      for (int k = 0; k < 3; ++k) vr[k] = vp(3 + k, l) - rw[k];
      mul3(E, wp, w);
      mul3(E, vr, vl);
    }
    const double aq[3] = {a[0] * qdj, a[1] * qdj, a[2] * qdj};  // the joint's rate along its axis
    double cw[3] = {0.0, 0.0, 0.0}, cv[3] = {0.0, 0.0, 0.0};
    if constexpr (J == JointType::kRevolute) {
      for (int k = 0; k < 3; ++k) w[k] += aq[k];
      // c = v × [aq; 0] = [w × aq; vl × aq]
      cross3(w, aq, cw);
      cross3(vl, aq, cv);
    } else if constexpr (J == JointType::kPrismatic) {
      for (int k = 0; k < 3; ++k) vl[k] += aq[k];
      // c = v × [0; aq] = [0; w × aq]
      cross3(w, aq, cv);
    }
    for (int k = 0; k < 3; ++k) v(k, l) = w[k], v(3 + k, l) = vl[k], c(k, l) = cw[k], c(3 + k, l) = cv[k];
    // The rigid inertia I = [Ibar, [h]×; [h]×^T, m 1] (RBDA eq. 2.63) and p = v ×* (I v):
    // I v = [Ibar w + h × vl; m vl - h × w],  v ×* [n; f] = [w × n + vl × f; w × f].
    const double m = In(0, l), h[3] = {In(1, l), In(2, l), In(3, l)};
    double Ib[9];
    const double Ip[6] = {In(4, l), In(5, l), In(6, l), In(7, l), In(8, l), In(9, l)};
    unpack_sym(Ip, Ib);
    double n[3], f[3], hv[3], hw[3];
    mul3(Ib, w, n);
    cross3(h, vl, hv);
    cross3(h, w, hw);
    for (int k = 0; k < 3; ++k) n[k] += hv[k], f[k] = m * vl[k] - hw[k];
    double wn[3], vf[3], wf[3];
    cross3(w, n, wn);
    cross3(vl, f, vf);
    cross3(w, f, wf);
    for (int k = 0; k < 3; ++k) pA(k, l) = wn[k] + vf[k], pA(3 + k, l) = wf[k];
    // I^A = I: A = Ibar (packed), B = [h]×, C = m 1 (packed).
    for (int k = 0; k < 6; ++k) IA(k, l) = Ip[k];
    const double B[9] = {0.0, -h[2], h[1], h[2], 0.0, -h[0], -h[1], h[0], 0.0};
    for (int k = 0; k < 9; ++k) IA(6 + k, l) = B[k];
    const double C[6] = {m, 0.0, 0.0, m, 0.0, m};
    for (int k = 0; k < 6; ++k) IA(15 + k, l) = C[k];
  }
}

// Pass 2 for body i, tip to root: U = I^A S, d = S^T U + armature, u = tau - S^T p^A; then the
// articulated inertia and bias force handed to the parent, I^a = I^A - U U^T / d and
// p^a = p^A + I^a c + U u / d, carried to its coordinates by X^T I^a X and X^T p^a (RBDA Table 7.1).
// X^T [A B; B^T C] X with X = rot(E) xlt(r): first A' = E^T A E (likewise B', C'), then
//   A'' = A' + r× B'^T - B' r× - r× C' r×,  B'' = B' + r× C',  C'' = C'.
template <JointType J, bool kRoot>
void aba_pass2(const TreeLanes& tl, int i, const double* tau, const double* extra, TreeLanesWorkspace& ws) {
  const int W = tl.W, p = tl.parent[i], j = tl.dof[i];
  const ConstLaneBlock ax = block(tl.axis, i, 3, W);
  const LaneBlock IA = block(ws.IA, i, 21, W), pA = block(ws.pA, i, 6, W), U = block(ws.U, i, 6, W);
  const LaneBlock c = block(ws.c, i, 6, W), Xup = block(ws.Xup, i, 12, W);
  const LaneBlock IAp = block(ws.IA, p < 0 ? 0 : p, 21, W), pAp = block(ws.pA, p < 0 ? 0 : p, 6, W);
  double* d = ws.d.data() + static_cast<std::size_t>(i) * W;
  double* u = ws.u.data() + static_cast<std::size_t>(i) * W;
  const double* arm = tl.armature.data() + static_cast<std::size_t>(j < 0 ? 0 : j) * W;
  const double* xarm = extra + static_cast<std::size_t>(j < 0 ? 0 : j) * W;  // zeros when none
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    double A[9], B[9], C[9], pa[6];
    double Ap[6], Cp[6];
    for (int k = 0; k < 6; ++k) Ap[k] = IA(k, l), Cp[k] = IA(15 + k, l), pa[k] = pA(k, l);
    unpack_sym(Ap, A);
    unpack_sym(Cp, C);
    for (int k = 0; k < 9; ++k) B[k] = IA(6 + k, l);
    if constexpr (J != JointType::kFixed) {
      const double a[3] = {ax(0, l), ax(1, l), ax(2, l)};
      double Ut[3], Ub[3];  // U = [A a; B^T a] (revolute) or [B a; C a] (prismatic)
      double uj;
      if constexpr (J == JointType::kRevolute) {
        mul3(A, a, Ut);
        mul3t(B, a, Ub);
        d[l] = dot3(a, Ut) + arm[l];
        uj = tau[j * W + l] - dot3(a, pa);
      } else {
        mul3(B, a, Ut);
        mul3(C, a, Ub);
        d[l] = dot3(a, Ub) + arm[l];
        uj = tau[j * W + l] - dot3(a, pa + 3);
      }
      d[l] += xarm[l];
      u[l] = uj;
      for (int k = 0; k < 3; ++k) U(k, l) = Ut[k], U(3 + k, l) = Ub[k];
      if constexpr (!kRoot) {
        const double dinv = 1.0 / d[l];
        const double Us[6] = {Ut[0], Ut[1], Ut[2], Ub[0], Ub[1], Ub[2]};
        for (int r = 0; r < 3; ++r)
          for (int k = 0; k < 3; ++k) {
            A[3 * r + k] -= Us[r] * dinv * Us[k];
            B[3 * r + k] -= Us[r] * dinv * Us[3 + k];
            C[3 * r + k] -= Us[3 + r] * dinv * Us[3 + k];
          }
        // p^a = p^A + I^a c + U u / d
        const double cc[6] = {c(0, l), c(1, l), c(2, l), c(3, l), c(4, l), c(5, l)};
        double t0[3], t1[3], t2[3], t3[3];
        mul3(A, cc, t0);
        mul3(B, cc + 3, t1);
        mul3t(B, cc, t2);
        mul3(C, cc + 3, t3);
        const double ud = uj * dinv;
        for (int k = 0; k < 3; ++k) {
          pa[k] += t0[k] + t1[k] + Us[k] * ud;
          pa[3 + k] += t2[k] + t3[k] + Us[3 + k] * ud;
        }
      }
    }
    if constexpr (!kRoot) {
      double E[9], r[3];
      for (int k = 0; k < 9; ++k) E[k] = Xup(k, l);
      for (int k = 0; k < 3; ++k) r[k] = Xup(9 + k, l);
      double A1[9], B1[9], C1[9];
      congruence3(E, A, A1);
      congruence3(E, B, B1);
      congruence3(E, C, C1);
      // r× M and M r× for 3x3 M: (r× M)_rk = (r × M_col k)_r, (M r×) = -(r× M^T)^T.
      const double R[9] = {0.0, -r[2], r[1], r[2], 0.0, -r[0], -r[1], r[0], 0.0};
      double RC[9], RBt[9], BR[9], RCR[9], B1t[9];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) B1t[3 * a + b] = B1[3 * b + a];
      matmul3(R, C1, RC);
      matmul3(R, B1t, RBt);
      matmul3(B1, R, BR);
      matmul3(RC, R, RCR);
      // Accumulate into the parent: packed A, full B, packed C.
      const int pk[6] = {0, 1, 2, 4, 5, 8};
      for (int k = 0; k < 6; ++k) {
        const int e = pk[k];
        IAp(k, l) += A1[e] + RBt[e] - BR[e] - RCR[e];
        IAp(15 + k, l) += C1[e];
      }
      for (int k = 0; k < 9; ++k) IAp(6 + k, l) += B1[k] + RC[k];
      // X^T [n; f] = [E^T n + r × E^T f; E^T f]
      double n1[3], f1[3], rf[3];
      mul3t(E, pa, n1);
      mul3t(E, pa + 3, f1);
      cross3(r, f1, rf);
      for (int k = 0; k < 3; ++k) pAp(k, l) += n1[k] + rf[k], pAp(3 + k, l) += f1[k];
    }
  }
}

// Pass 3 for body i, root to tip: a = Xup a_parent + c (the base's a_0 = [0; -gravity]),
// qdd = (u - U . a) / d, a += S qdd.
template <JointType J, bool kRoot>
void aba_pass3(const TreeLanes& tl, int i, double* qdd, TreeLanesWorkspace& ws) {
  const int W = tl.W, p = tl.parent[i], j = tl.dof[i];
  const ConstLaneBlock ax = block(tl.axis, i, 3, W), Xup = block(ws.Xup, i, 12, W), c = block(ws.c, i, 6, W);
  const ConstLaneBlock U = block(ws.U, i, 6, W), ap = block(ws.a, p < 0 ? 0 : p, 6, W);
  const ConstLaneBlock g(tl.gravity.data(), W);
  const LaneBlock a = block(ws.a, i, 6, W);
  const double* d = ws.d.data() + static_cast<std::size_t>(i) * W;
  const double* u = ws.u.data() + static_cast<std::size_t>(i) * W;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    double E[9], r[3], wp[3], vp[3];
    for (int k = 0; k < 9; ++k) E[k] = Xup(k, l);
    for (int k = 0; k < 3; ++k) r[k] = Xup(9 + k, l);
    if constexpr (kRoot) {
      for (int k = 0; k < 3; ++k) wp[k] = 0.0, vp[k] = -g(k, l);
    } else {
      for (int k = 0; k < 3; ++k) wp[k] = ap(k, l), vp[k] = ap(3 + k, l);
    }
    double rw[3], vr[3], aw[3], av[3];
    cross3(r, wp, rw);
    for (int k = 0; k < 3; ++k) vr[k] = vp[k] - rw[k];
    mul3(E, wp, aw);
    mul3(E, vr, av);
    for (int k = 0; k < 3; ++k) aw[k] += c(k, l), av[k] += c(3 + k, l);
    if constexpr (J != JointType::kFixed) {
      double Ua = 0.0;
      for (int k = 0; k < 3; ++k) Ua += U(k, l) * aw[k];
      for (int k = 0; k < 3; ++k) Ua += U(3 + k, l) * av[k];
      const double x = (u[l] - Ua) / d[l];
      qdd[j * W + l] = x;
      for (int k = 0; k < 3; ++k) {
        if constexpr (J == JointType::kRevolute)
          aw[k] += ax(k, l) * x;
        else
          av[k] += ax(k, l) * x;
      }
    }
    for (int k = 0; k < 3; ++k) a(k, l) = aw[k], a(3 + k, l) = av[k];
  }
}

template <template <JointType, bool> class F, class... Args>
void by_joint(JointType t, bool root, Args&&... args) {
  switch (t) {
    case JointType::kRevolute:
      root ? F<JointType::kRevolute, true>::run(args...) : F<JointType::kRevolute, false>::run(args...);
      break;
    case JointType::kPrismatic:
      root ? F<JointType::kPrismatic, true>::run(args...) : F<JointType::kPrismatic, false>::run(args...);
      break;
    case JointType::kFixed:
      root ? F<JointType::kFixed, true>::run(args...) : F<JointType::kFixed, false>::run(args...);
      break;
  }
}
template <JointType J, bool R> struct Pass1 { static void run(auto&&... a) { aba_pass1<J, R>(a...); } };
template <JointType J, bool R> struct Pass2 { static void run(auto&&... a) { aba_pass2<J, R>(a...); } };
template <JointType J, bool R> struct Pass3 { static void run(auto&&... a) { aba_pass3<J, R>(a...); } };

}  // namespace

TreeLanes make_tree_lanes(std::span<const Tree> trees) {
  if (trees.empty()) throw std::invalid_argument("make_tree_lanes: no trees");
  if (trees.size() > static_cast<std::size_t>(kMaxTreeLanes))
    throw std::invalid_argument("make_tree_lanes: " + std::to_string(trees.size()) + " trees, at most " +
                                std::to_string(kMaxTreeLanes) + " lanes");
  const Tree& t0 = trees[0];
  TreeLanes tl;
  tl.W = static_cast<int>(trees.size());
  tl.nb = t0.num_bodies();
  tl.nv = t0.nv();
  tl.trees.assign(trees.begin(), trees.end());
  for (const Body& b : t0.bodies()) {
    tl.parent.push_back(b.parent);
    tl.dof.push_back(b.dof);
    tl.joint.push_back(b.joint);
  }
  const int W = tl.W, nb = tl.nb, nv = tl.nv;
  const auto sz = [W](int n, int K) { return static_cast<std::size_t>(n) * K * W; };
  tl.axis.assign(sz(nb, 3), 0.0);
  tl.X_tree.assign(sz(nb, 12), 0.0);
  tl.inertia.assign(sz(nb, 10), 0.0);
  for (auto* v : {&tl.armature, &tl.stiffness, &tl.damping, &tl.spring_reference}) v->assign(sz(nv, 1), 0.0);
  tl.gravity.assign(sz(1, 3), 0.0);
  for (int l = 0; l < W; ++l) {
    const Tree& t = trees[static_cast<std::size_t>(l)];
    if (t.num_bodies() != nb)
      throw std::invalid_argument("make_tree_lanes: lane " + std::to_string(l) + " has " +
                                  std::to_string(t.num_bodies()) + " bodies, lane 0 has " + std::to_string(nb));
    for (int k = 0; k < 3; ++k) tl.gravity[static_cast<std::size_t>(k) * W + l] = t.gravity()[k];
    for (int i = 0; i < nb; ++i) {
      const Body& b = t.body(i);
      if (b.parent != tl.parent[i] || b.joint != tl.joint[i] || b.dof != tl.dof[i])
        throw std::invalid_argument("make_tree_lanes: lane " + std::to_string(l) + ", body " + std::to_string(i) +
                                    " (" + b.name + "): another parent or joint type than in lane 0");
      const LaneBlock ax = block(tl.axis, i, 3, W), Xt = block(tl.X_tree, i, 12, W), In = block(tl.inertia, i, 10, W);
      for (int k = 0; k < 3; ++k) ax(k, l) = b.axis[k];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) Xt(3 * r + c, l) = b.X_tree.E(r, c);
      for (int k = 0; k < 3; ++k) Xt(9 + k, l) = b.X_tree.r[k];
      const Mat3 Ibar = b.inertia.topLeftCorner<3, 3>();
      const Vec3 h = b.mass * b.com;
      In(0, l) = b.mass;
      for (int k = 0; k < 3; ++k) In(1 + k, l) = h[k];
      const double packed[6] = {Ibar(0, 0), Ibar(0, 1), Ibar(0, 2), Ibar(1, 1), Ibar(1, 2), Ibar(2, 2)};
      for (int k = 0; k < 6; ++k) In(4 + k, l) = packed[k];
      if (b.dof >= 0) {
        const std::size_t o = static_cast<std::size_t>(b.dof) * W + l;
        tl.armature[o] = b.armature;
        tl.stiffness[o] = b.stiffness;
        tl.damping[o] = b.damping;
        tl.spring_reference[o] = b.spring_reference;
      }
    }
  }
  return tl;
}

TreeLanesWorkspace::TreeLanesWorkspace(const TreeLanes& tl) : W(tl.W), nb(tl.nb), nv(tl.nv) {
  const std::size_t n = static_cast<std::size_t>(tl.nb) * tl.W;
  Xup.assign(12 * n, 0.0);
  v.assign(6 * n, 0.0);
  c.assign(6 * n, 0.0);
  a.assign(6 * n, 0.0);
  IA.assign(21 * n, 0.0);
  pA.assign(6 * n, 0.0);
  U.assign(6 * n, 0.0);
  d.assign(n, 1.0);
  u.assign(n, 0.0);
  zeros.assign(static_cast<std::size_t>(tl.nv) * tl.W, 0.0);
}

void compute_tree_forward_dynamics(const TreeLanes& tl, const double* q, const double* qd, const double* tau,
                                   const double* extra_armature, double* qdd, TreeLanesWorkspace& ws) {
  if (ws.W != tl.W || ws.nb != tl.nb)
    throw std::invalid_argument("compute_tree_forward_dynamics: the workspace was made for another batch");
  const double* extra = extra_armature ? extra_armature : ws.zeros.data();
  for (int i = 0; i < tl.nb; ++i) by_joint<Pass1>(tl.joint[i], tl.parent[i] < 0, tl, i, q, qd, ws);
  for (int i = tl.nb - 1; i >= 0; --i) by_joint<Pass2>(tl.joint[i], tl.parent[i] < 0, tl, i, tau, extra, ws);
  for (int i = 0; i < tl.nb; ++i) by_joint<Pass3>(tl.joint[i], tl.parent[i] < 0, tl, i, qdd, ws);
}

void compute_tree_passive_forces(const TreeLanes& tl, const double* q, const double* qd, const double* tau_applied,
                                 double* tau) {
  const std::size_t n = static_cast<std::size_t>(tl.nv) * tl.W;
  const double *k = tl.stiffness.data(), *c = tl.damping.data(), *q0 = tl.spring_reference.data();
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    const double t = -k[j] * (q[j] - q0[j]) - c[j] * qd[j];
    tau[j] = tau_applied ? tau_applied[j] + t : t;
  }
}

}  // namespace ff
