#include "multibody/lanes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/isa.hpp"
#include "kernel/fastmath.hpp"

namespace ff {

namespace {

#define FF_INLINE [[gnu::always_inline]] inline

// The lane loops are written in scalar locals only (x0, x1, x2 for a 3-vector, M0..M8 for a 3x3
// row-major matrix, each a `double`): GCC vectorises a loop over lanes written so, and not one that
// keeps its small vectors in local arrays or structs. The macros below spell the 3-vector and 3x3
// operations on such names; each declares its result.
#define FF_V3(o, e0, e1, e2) [[maybe_unused]] double o##0 = (e0), o##1 = (e1), o##2 = (e2)
#define FF_LOAD3(o, base, k) FF_V3(o, base[(k) * sW + l], base[((k) + 1) * sW + l], base[((k) + 2) * sW + l])
#define FF_STORE3(base, k, v) \
  base[(k) * sW + l] = v##0, base[((k) + 1) * sW + l] = v##1, base[((k) + 2) * sW + l] = v##2
#define FF_CROSS(o, a, b) FF_V3(o, a##1 * b##2 - a##2 * b##1, a##2 * b##0 - a##0 * b##2, a##0 * b##1 - a##1 * b##0)
// o = M x and o = M^T x
#define FF_MV(o, M, x) \
  FF_V3(o, M##0 * x##0 + M##1 * x##1 + M##2 * x##2, M##3 * x##0 + M##4 * x##1 + M##5 * x##2, \
        M##6 * x##0 + M##7 * x##1 + M##8 * x##2)
#define FF_MTV(o, M, x) \
  FF_V3(o, M##0 * x##0 + M##3 * x##1 + M##6 * x##2, M##1 * x##0 + M##4 * x##1 + M##7 * x##2, \
        M##2 * x##0 + M##5 * x##1 + M##8 * x##2)
// 3x3 matrices: declare from nine values, products A B and A^T B.
#define FF_M3(o, e0, e1, e2, e3, e4, e5, e6, e7, e8) \
  [[maybe_unused]] double o##0 = (e0), o##1 = (e1), o##2 = (e2), o##3 = (e3), o##4 = (e4), o##5 = (e5), o##6 = (e6), \
         o##7 = (e7), o##8 = (e8)
// Entry (r, c) of a matrix named M is M##(3r + c); each product spells out its nine entries.
#define FF_MM(o, A, B) \
  FF_M3(o, A##0 * B##0 + A##1 * B##3 + A##2 * B##6, A##0 * B##1 + A##1 * B##4 + A##2 * B##7, \
        A##0 * B##2 + A##1 * B##5 + A##2 * B##8, A##3 * B##0 + A##4 * B##3 + A##5 * B##6, \
        A##3 * B##1 + A##4 * B##4 + A##5 * B##7, A##3 * B##2 + A##4 * B##5 + A##5 * B##8, \
        A##6 * B##0 + A##7 * B##3 + A##8 * B##6, A##6 * B##1 + A##7 * B##4 + A##8 * B##7, \
        A##6 * B##2 + A##7 * B##5 + A##8 * B##8)
#define FF_MTM(o, A, B) \
  FF_M3(o, A##0 * B##0 + A##3 * B##3 + A##6 * B##6, A##0 * B##1 + A##3 * B##4 + A##6 * B##7, \
        A##0 * B##2 + A##3 * B##5 + A##6 * B##8, A##1 * B##0 + A##4 * B##3 + A##7 * B##6, \
        A##1 * B##1 + A##4 * B##4 + A##7 * B##7, A##1 * B##2 + A##4 * B##5 + A##7 * B##8, \
        A##2 * B##0 + A##5 * B##3 + A##8 * B##6, A##2 * B##1 + A##5 * B##4 + A##8 * B##7, \
        A##2 * B##2 + A##5 * B##5 + A##8 * B##8)
// Nine components k.. of a block as a 3x3 M0..M8.
#define FF_LOAD9(o, base, k)                                                                                  \
  FF_M3(o, base[(k) * sW + l], base[((k) + 1) * sW + l], base[((k) + 2) * sW + l], base[((k) + 3) * sW + l], \
        base[((k) + 4) * sW + l], base[((k) + 5) * sW + l], base[((k) + 6) * sW + l], base[((k) + 7) * sW + l], \
        base[((k) + 8) * sW + l])

// Component k of body i's K-vector block in lane l is at blk(v, i, K)[k * W + l].
// (On 64-byte boundaries, LaneArray: said to the compiler, which then neither peels nor checks.)
FF_INLINE double* blk(LaneArray& v, int i, int K, std::size_t W) {
  return static_cast<double*>(__builtin_assume_aligned(v.data(), 64)) + static_cast<std::size_t>(i) * K * W;
}
FF_INLINE const double* blk(const LaneArray& v, int i, int K, std::size_t W) {
  return static_cast<const double*>(__builtin_assume_aligned(v.data(), 64)) + static_cast<std::size_t>(i) * K * W;
}

// Packed symmetric 3x3 (xx, xy, xz, yy, yz, zz) as o0..o5, loaded from components k.., and the full
// matrix M0..M8 (entry (r, c) at 3r + c) of such a packed o.
#define FF_LOAD_PACKED(o, base, k)                                                                         \
  [[maybe_unused]] double o##0 = base[(k) * sW + l], o##1 = base[((k) + 1) * sW + l],                     \
                          o##2 = base[((k) + 2) * sW + l], o##3 = base[((k) + 3) * sW + l],               \
                          o##4 = base[((k) + 4) * sW + l], o##5 = base[((k) + 5) * sW + l]
#define FF_FULL(M, o) FF_M3(M, o##0, o##1, o##2, o##1, o##3, o##4, o##2, o##4, o##5)
// o = E^T N, packed: only the upper triangle of a product known to be symmetric (E^T S E).
#define FF_MTM_SYM(o, E, N)                                                                                     \
  [[maybe_unused]] const double o##0 = E##0 * N##0 + E##3 * N##3 + E##6 * N##6,                                \
                                o##1 = E##0 * N##1 + E##3 * N##4 + E##6 * N##7,                                \
                                o##2 = E##0 * N##2 + E##3 * N##5 + E##6 * N##8,                                \
                                o##3 = E##1 * N##1 + E##4 * N##4 + E##7 * N##7,                                \
                                o##4 = E##1 * N##2 + E##4 * N##5 + E##7 * N##8,                                \
                                o##5 = E##2 * N##2 + E##5 * N##5 + E##8 * N##8
// o = r× M (rows: r × each column of M)
#define FF_RX_M(o, r, M)                                                                                       \
  FF_M3(o, r##1 * M##6 - r##2 * M##3, r##1 * M##7 - r##2 * M##4, r##1 * M##8 - r##2 * M##5,                  \
        r##2 * M##0 - r##0 * M##6, r##2 * M##1 - r##0 * M##7, r##2 * M##2 - r##0 * M##8,                      \
        r##0 * M##3 - r##1 * M##0, r##0 * M##4 - r##1 * M##1, r##0 * M##5 - r##1 * M##2)
// (ow, ov) = X m = [E w; E (v - r × w)] (RBDA eq. 2.24) for the motion vector m at components 0..5 of mb.
#define FF_XMOTION(ow, ov, E, r, mb)                                                                          \
  FF_LOAD3(ow##_w, mb, 0);                                                                                    \
  FF_CROSS(ow##_rw, r, ow##_w);                                                                               \
  FF_V3(ow##_vr, mb[3 * sW + l] - ow##_rw0, mb[4 * sW + l] - ow##_rw1, mb[5 * sW + l] - ow##_rw2);           \
  FF_MV(ow, E, ow##_w);                                                                                       \
  FF_MV(ov, E, ow##_vr)
// o_i = (row i of M) × r (left = 0) or r × (row i of M) (left = 1), i = 0, 1, 2, as o0.., o1.., o2..
#define FF_ROW_CROSS(o, x, r, left) \
  FF_V3(o, left ? r##1 * x##2 - r##2 * x##1 : x##1 * r##2 - x##2 * r##1, \
        left ? r##2 * x##0 - r##0 * x##2 : x##2 * r##0 - x##0 * r##2, left ? r##0 * x##1 - r##1 * x##0 : x##0 * r##1 - x##1 * r##0)
#define FF_ROWS_CROSS(o, M, r, left)                       \
  FF_V3(o##_m0, M##0, M##1, M##2);                         \
  FF_V3(o##_m1, M##3, M##4, M##5);                         \
  FF_V3(o##_m2, M##6, M##7, M##8);                         \
  FF_ROW_CROSS(o##0, o##_m0, r, left);                     \
  FF_ROW_CROSS(o##1, o##_m1, r, left);                     \
  FF_ROW_CROSS(o##2, o##_m2, r, left)
// M -= x y^T
#define FF_SUB_XYT(M, x, y)                                                                                    \
  M##0 -= x##0 * y##0, M##1 -= x##0 * y##1, M##2 -= x##0 * y##2, M##3 -= x##1 * y##0, M##4 -= x##1 * y##1,     \
  M##5 -= x##1 * y##2, M##6 -= x##2 * y##0, M##7 -= x##2 * y##1, M##8 -= x##2 * y##2

// Pass 1 of the ABA for body i, root to tip, in every lane, in the body's joint frame (its joint axis
// z, TreeLanes): the joint transform Xup = X_J(q) X_tree, the velocity v = Xup v_parent + S qd,
// c = v × S qd, and the rigid body's inertia and bias force p = v ×* I v as the start of the
// articulated quantities (RBDA Table 7.1, first loop).
template <JointType J, bool kRoot, int kW>
FF_INLINE void aba_pass1(const TreeLanes& tl, int i, const double* q, const double* qd, TreeLanesWorkspace& ws) {
  const std::size_t sW = static_cast<std::size_t>(kW > 0 ? kW : tl.W);
  const int W = kW > 0 ? kW : tl.W, p = kRoot ? 0 : tl.parent[i], j = tl.dof[i] < 0 ? 0 : tl.dof[i];
  const double *Xtb = blk(tl.X_tree, i, 12, sW), *Inb = blk(tl.inertia, i, 10, sW);
  const double* vpb = blk(ws.v, p, 6, sW);
  double *Xb = blk(ws.Xup, i, 12, sW), *vb = blk(ws.v, i, 6, sW), *cb = blk(ws.c, i, 4, sW);
  double *IAb = blk(ws.IA, i, 21, sW), *pAb = blk(ws.pA, i, 6, sW);
  const double *qj = q + j * sW, *qdj = qd + j * sW;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    FF_LOAD9(E, Xtb, 0);
    FF_LOAD3(r, Xtb, 9);
    // Joint transform about z. Revolute: E = E_J E_tree with E_J = rz(q) = [c s 0; -s c 0; 0 0 1]
    // (RBDA Table 2.2): rows 0 and 1 of E_tree turn, row 2 stays; prismatic: r = r_tree + E_tree^T [0 0 q].
    double qdl = 0.0;
    if constexpr (J == JointType::kRevolute) {
      double s, co;
      calc_sincos(qj[l], s, co);
      const double e0 = co * E0 + s * E3, e1 = co * E1 + s * E4, e2 = co * E2 + s * E5;
      E3 = co * E3 - s * E0, E4 = co * E4 - s * E1, E5 = co * E5 - s * E2;
      E0 = e0, E1 = e1, E2 = e2;
      qdl = qdj[l];
    } else if constexpr (J == JointType::kPrismatic) {
      const double ql = qj[l];
      r0 += E6 * ql, r1 += E7 * ql, r2 += E8 * ql;
      qdl = qdj[l];
    }
    Xb[0 * sW + l] = E0, Xb[1 * sW + l] = E1, Xb[2 * sW + l] = E2, Xb[3 * sW + l] = E3, Xb[4 * sW + l] = E4;
    Xb[5 * sW + l] = E5, Xb[6 * sW + l] = E6, Xb[7 * sW + l] = E7, Xb[8 * sW + l] = E8;
    FF_STORE3(Xb, 9, r);
    // v = Xup v_parent + S qd: [E w; E (v - r × w)] (the base is at rest).
    FF_V3(w, 0.0, 0.0, 0.0);
    FF_V3(vl, 0.0, 0.0, 0.0);
    if constexpr (!kRoot) {
      FF_XMOTION(Ew, Ev, E, r, vpb);
      w0 = Ew0, w1 = Ew1, w2 = Ew2, vl0 = Ev0, vl1 = Ev1, vl2 = Ev2;
    }
    // c = v × S qd, S qd = [0 0 qd 0 0 0] or [0 0 0 0 0 qd]: its z components are zero, the rest kept
    // as (c_wx, c_wy, c_vx, c_vy). Revolute: [w × z qd; vl × z qd]; prismatic: [0; w × z qd].
    if constexpr (J == JointType::kRevolute) {
      w2 += qdl;
      cb[0 * sW + l] = w1 * qdl, cb[1 * sW + l] = -(w0 * qdl);
      cb[2 * sW + l] = vl1 * qdl, cb[3 * sW + l] = -(vl0 * qdl);
    } else if constexpr (J == JointType::kPrismatic) {
      vl2 += qdl;
      cb[2 * sW + l] = w1 * qdl, cb[3 * sW + l] = -(w0 * qdl);
    }
    FF_STORE3(vb, 0, w);
    FF_STORE3(vb, 3, vl);
    // The rigid inertia I = [Ibar, [h]×; [h]×^T, m 1] (RBDA eq. 2.63) and p = v ×* (I v):
    // I v = [Ibar w + h × vl; m vl - h × w],  v ×* [n; f] = [w × n + vl × f; w × f].
    const double m = Inb[0 * sW + l];
    FF_LOAD3(h, Inb, 1);
    FF_LOAD_PACKED(Ibp, Inb, 4);
    FF_FULL(Ib, Ibp);
    FF_MV(Iw, Ib, w);
    FF_CROSS(hv, h, vl);
    FF_CROSS(hw, h, w);
    FF_V3(n, Iw0 + hv0, Iw1 + hv1, Iw2 + hv2);
    FF_V3(f, m * vl0 - hw0, m * vl1 - hw1, m * vl2 - hw2);
    FF_CROSS(wn, w, n);
    FF_CROSS(vf, vl, f);
    FF_CROSS(wf, w, f);
    FF_V3(pt, wn0 + vf0, wn1 + vf1, wn2 + vf2);
    FF_STORE3(pAb, 0, pt);
    FF_STORE3(pAb, 3, wf);
    // I^A = I: A = Ibar (packed), B = [h]×, C = m 1 (packed).
    IAb[0 * sW + l] = Ibp0, IAb[1 * sW + l] = Ibp1, IAb[2 * sW + l] = Ibp2;
    IAb[3 * sW + l] = Ibp3, IAb[4 * sW + l] = Ibp4, IAb[5 * sW + l] = Ibp5;
    IAb[6 * sW + l] = 0.0, IAb[7 * sW + l] = -h2, IAb[8 * sW + l] = h1;
    IAb[9 * sW + l] = h2, IAb[10 * sW + l] = 0.0, IAb[11 * sW + l] = -h0;
    IAb[12 * sW + l] = -h1, IAb[13 * sW + l] = h0, IAb[14 * sW + l] = 0.0;
    IAb[15 * sW + l] = m, IAb[16 * sW + l] = 0.0, IAb[17 * sW + l] = 0.0;
    IAb[18 * sW + l] = m, IAb[19 * sW + l] = 0.0, IAb[20 * sW + l] = m;
  }
}

// Pass 2 for body i, tip to root (RBDA Table 7.1, second loop). The joint's column of I^A = [A B; B^T C]
// is U = I^A S: [A_z; B_z row] (revolute) or [B_z col; C_z] (prismatic), no product; d = U_z + armature,
// u = tau - S^T p^A. Then the articulated inertia and bias force handed to the parent,
// I^a = I^A - U U^T / d (symmetric: 21 entries) and p^a = p^A + I^a c + U u / d, carried to its
// coordinates by X^T I^a X and X^T p^a. X^T [A B; B^T C] X with X = rot(E) xlt(r) (RBDA eq. 2.66):
// first A' = E^T A E (likewise B', C'; A', C' symmetric), then with B'' = B' + r× C'
//   A'' = A' - B' r× + r× B''^T  (= A' + r× B'^T - B' r× - r× C' r×),  C'' = C'.
template <JointType J, bool kRoot, int kW>
FF_INLINE void aba_pass2(const TreeLanes& tl, int i, const double* tau, const double* extra, TreeLanesWorkspace& ws) {
  const std::size_t sW = static_cast<std::size_t>(kW > 0 ? kW : tl.W);
  const int W = kW > 0 ? kW : tl.W, p = kRoot ? 0 : tl.parent[i], j = tl.dof[i] < 0 ? 0 : tl.dof[i];
  const double *IAb = blk(ws.IA, i, 21, sW), *pAb = blk(ws.pA, i, 6, sW);
  const double *cb = blk(ws.c, i, 4, sW), *Xb = blk(ws.Xup, i, 12, sW);
  double *IApb = blk(ws.IA, p, 21, sW), *pApb = blk(ws.pA, p, 6, sW);
  double* d = ws.d.data() + static_cast<std::size_t>(i) * sW;
  double* u = ws.u.data() + static_cast<std::size_t>(i) * sW;
  const double *arm = tl.armature.data() + j * sW, *xarm = extra + j * sW, *tj = tau + j * sW;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    FF_LOAD_PACKED(A, IAb, 0);
    FF_LOAD9(B, IAb, 6);
    FF_LOAD_PACKED(C, IAb, 15);
    FF_LOAD3(pt, pAb, 0);
    FF_LOAD3(pb, pAb, 3);
    if constexpr (J != JointType::kFixed) {
      FF_V3(Ut, 0.0, 0.0, 0.0);
      FF_V3(Uq, 0.0, 0.0, 0.0);
      double dl, ul;
      if constexpr (J == JointType::kRevolute) {
        Ut0 = A2, Ut1 = A4, Ut2 = A5, Uq0 = B6, Uq1 = B7, Uq2 = B8;
        dl = A5 + arm[l];
        ul = tj[l] - pt2;
      } else {
        Ut0 = B2, Ut1 = B5, Ut2 = B8, Uq0 = C2, Uq1 = C4, Uq2 = C5;
        dl = C5 + arm[l];
        ul = tj[l] - pb2;
      }
      dl += xarm[l];
      d[l] = dl;
      u[l] = ul;
      if constexpr (!kRoot) {
        const double dinv = 1.0 / dl, ud = ul * dinv;
        FF_V3(wt, Ut0 * dinv, Ut1 * dinv, Ut2 * dinv);
        FF_V3(wq, Uq0 * dinv, Uq1 * dinv, Uq2 * dinv);
        A0 -= wt0 * Ut0, A1 -= wt0 * Ut1, A2 -= wt0 * Ut2, A3 -= wt1 * Ut1, A4 -= wt1 * Ut2, A5 -= wt2 * Ut2;
        FF_SUB_XYT(B, wt, Uq);
        C0 -= wq0 * Uq0, C1 -= wq0 * Uq1, C2 -= wq0 * Uq2, C3 -= wq1 * Uq1, C4 -= wq1 * Uq2, C5 -= wq2 * Uq2;
        // p^a = p^A + I^a c + U u / d over c's x and y components (A, C packed: (r, c) of A at
        // 0 1 2 / 1 3 4 / 2 4 5).
        const double cv0 = cb[2 * sW + l], cv1 = cb[3 * sW + l];
        if constexpr (J == JointType::kRevolute) {
          const double cw0 = cb[0 * sW + l], cw1 = cb[1 * sW + l];
          pt0 += A0 * cw0 + A1 * cw1 + B0 * cv0 + B1 * cv1 + Ut0 * ud;
          pt1 += A1 * cw0 + A3 * cw1 + B3 * cv0 + B4 * cv1 + Ut1 * ud;
          pt2 += A2 * cw0 + A4 * cw1 + B6 * cv0 + B7 * cv1 + Ut2 * ud;
          pb0 += B0 * cw0 + B3 * cw1 + C0 * cv0 + C1 * cv1 + Uq0 * ud;
          pb1 += B1 * cw0 + B4 * cw1 + C1 * cv0 + C3 * cv1 + Uq1 * ud;
          pb2 += B2 * cw0 + B5 * cw1 + C2 * cv0 + C4 * cv1 + Uq2 * ud;
        } else {
          pt0 += B0 * cv0 + B1 * cv1 + Ut0 * ud;
          pt1 += B3 * cv0 + B4 * cv1 + Ut1 * ud;
          pt2 += B6 * cv0 + B7 * cv1 + Ut2 * ud;
          pb0 += C0 * cv0 + C1 * cv1 + Uq0 * ud;
          pb1 += C1 * cv0 + C3 * cv1 + Uq1 * ud;
          pb2 += C2 * cv0 + C4 * cv1 + Uq2 * ud;
        }
      }
    }
    if constexpr (!kRoot) {
      FF_LOAD9(E, Xb, 0);
      FF_LOAD3(r, Xb, 9);
      FF_FULL(Af, A);
      FF_FULL(Cf, C);
      FF_MM(AE, Af, E);
      FF_MTM_SYM(A1p, E, AE);
      FF_MM(BE, B, E);
      FF_MTM(B1, E, BE);
      FF_MM(CE, Cf, E);
      FF_MTM_SYM(C1p, E, CE);
      FF_FULL(C1, C1p);
      FF_RX_M(RC, r, C1);
      FF_M3(B2, B10 + RC0, B11 + RC1, B12 + RC2, B13 + RC3, B14 + RC4, B15 + RC5, B16 + RC6, B17 + RC7, B18 + RC8);
      // Row r of B' r× is (row r of B') × r = X_r; column c of r× B''^T is r × (row c of B'') = Y_c.
      FF_ROWS_CROSS(X, B1, r, 0);
      FF_ROWS_CROSS(Y, B2, r, 1);
      // Accumulate into the parent: packed A'' (entry (r, c) is A' - X_r[c] + Y_c[r]), full B'', packed C'.
      IApb[0 * sW + l] += A1p0 - X00 + Y00, IApb[1 * sW + l] += A1p1 - X01 + Y10;
      IApb[2 * sW + l] += A1p2 - X02 + Y20, IApb[3 * sW + l] += A1p3 - X11 + Y11;
      IApb[4 * sW + l] += A1p4 - X12 + Y21, IApb[5 * sW + l] += A1p5 - X22 + Y22;
      IApb[6 * sW + l] += B20, IApb[7 * sW + l] += B21, IApb[8 * sW + l] += B22;
      IApb[9 * sW + l] += B23, IApb[10 * sW + l] += B24, IApb[11 * sW + l] += B25;
      IApb[12 * sW + l] += B26, IApb[13 * sW + l] += B27, IApb[14 * sW + l] += B28;
      IApb[15 * sW + l] += C1p0, IApb[16 * sW + l] += C1p1, IApb[17 * sW + l] += C1p2;
      IApb[18 * sW + l] += C1p3, IApb[19 * sW + l] += C1p4, IApb[20 * sW + l] += C1p5;
      // X^T [n; f] = [E^T n + r × E^T f; E^T f]
      FF_MTV(n1, E, pt);
      FF_MTV(f1, E, pb);
      FF_CROSS(rf, r, f1);
      pApb[0 * sW + l] += n10 + rf0, pApb[1 * sW + l] += n11 + rf1, pApb[2 * sW + l] += n12 + rf2;
      pApb[3 * sW + l] += f10, pApb[4 * sW + l] += f11, pApb[5 * sW + l] += f12;
    }
  }
}

// Pass 3 for body i, root to tip: a = Xup a_parent + c (the base's a_0 = [0; -gravity]),
// qdd = (u - U . a) / d with U the joint's column of I^A (pass 2), a += S qdd (RBDA Table 7.1, third loop).
template <JointType J, bool kRoot, int kW>
FF_INLINE void aba_pass3(const TreeLanes& tl, int i, double* qdd, TreeLanesWorkspace& ws) {
  const std::size_t sW = static_cast<std::size_t>(kW > 0 ? kW : tl.W);
  const int W = kW > 0 ? kW : tl.W, p = kRoot ? 0 : tl.parent[i], j = tl.dof[i] < 0 ? 0 : tl.dof[i];
  const double *Xb = blk(ws.Xup, i, 12, sW), *cb = blk(ws.c, i, 4, sW), *IAb = blk(ws.IA, i, 21, sW);
  const double *apb = blk(ws.a, p, 6, sW), *gb = tl.gravity.data();
  double* ab = blk(ws.a, i, 6, sW);
  const double* d = ws.d.data() + static_cast<std::size_t>(i) * sW;
  const double* u = ws.u.data() + static_cast<std::size_t>(i) * sW;
  double* qj = qdd + j * sW;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    FF_LOAD9(E, Xb, 0);
    FF_V3(aw, 0.0, 0.0, 0.0);
    FF_V3(av, 0.0, 0.0, 0.0);
    if constexpr (kRoot) {
      FF_V3(g, -gb[0 * sW + l], -gb[1 * sW + l], -gb[2 * sW + l]);
      FF_MV(Eg, E, g);
      av0 = Eg0, av1 = Eg1, av2 = Eg2;
    } else {
      FF_LOAD3(r, Xb, 9);
      FF_XMOTION(Ew, Ev, E, r, apb);
      aw0 = Ew0, aw1 = Ew1, aw2 = Ew2, av0 = Ev0, av1 = Ev1, av2 = Ev2;
    }
    if constexpr (J != JointType::kFixed) {
      constexpr bool kRev = J == JointType::kRevolute;
      if constexpr (kRev) aw0 += cb[0 * sW + l], aw1 += cb[1 * sW + l];
      av0 += cb[2 * sW + l], av1 += cb[3 * sW + l];
      // U = [A_z; B row z] (IA components 2, 4, 5, 12, 13, 14) or [B col z; C_z] (8, 11, 14, 17, 19, 20)
      constexpr int k0 = kRev ? 2 : 8, k1 = kRev ? 4 : 11, k2 = kRev ? 5 : 14;
      constexpr int k3 = kRev ? 12 : 17, k4 = kRev ? 13 : 19, k5 = kRev ? 14 : 20;
      const double Ua = IAb[k0 * sW + l] * aw0 + IAb[k1 * sW + l] * aw1 + IAb[k2 * sW + l] * aw2 +
                        IAb[k3 * sW + l] * av0 + IAb[k4 * sW + l] * av1 + IAb[k5 * sW + l] * av2;
      const double x = (u[l] - Ua) / d[l];
      qj[l] = x;
      (kRev ? aw2 : av2) += x;
    }
    FF_STORE3(ab, 0, aw);
    FF_STORE3(ab, 3, av);
  }
}

// Runs F for body i's joint type. Not always_inline: forced inline (with the passes flattened into the
// clones anyway) GCC 12 made the rigid arm's ABA 1.6x slower.
template <template <JointType, bool, int> class F, int kW, class... Args>
void by_joint(JointType t, bool root, Args&&... args) {
  switch (t) {
    case JointType::kRevolute:
      root ? F<JointType::kRevolute, true, kW>::run(args...) : F<JointType::kRevolute, false, kW>::run(args...);
      break;
    case JointType::kPrismatic:
      root ? F<JointType::kPrismatic, true, kW>::run(args...) : F<JointType::kPrismatic, false, kW>::run(args...);
      break;
    case JointType::kFixed:
      root ? F<JointType::kFixed, true, kW>::run(args...) : F<JointType::kFixed, false, kW>::run(args...);
      break;
  }
}
template <JointType J, bool R, int kW> struct Pass1 { static void run(auto&&... a) { aba_pass1<J, R, kW>(a...); } };
template <JointType J, bool R, int kW> struct Pass2 { static void run(auto&&... a) { aba_pass2<J, R, kW>(a...); } };
template <JointType J, bool R, int kW> struct Pass3 { static void run(auto&&... a) { aba_pass3<J, R, kW>(a...); } };

// The three passes over every body; kW > 0: W = kW known at compile time (the lane loops' trip count
// and every component's offset constant), 0: any W.
template <int kW>
FF_INLINE void aba_passes(const TreeLanes& tl, const double* q, const double* qd, const double* tau,
                          const double* extra, double* qdd, TreeLanesWorkspace& ws) {
  for (int i = 0; i < tl.nb; ++i) by_joint<Pass1, kW>(tl.joint[i], tl.parent[i] < 0, tl, i, q, qd, ws);
  for (int i = tl.nb - 1; i >= 0; --i) by_joint<Pass2, kW>(tl.joint[i], tl.parent[i] < 0, tl, i, tau, extra, ws);
  for (int i = 0; i < tl.nb; ++i) by_joint<Pass3, kW>(tl.joint[i], tl.parent[i] < 0, tl, i, qdd, ws);
}

// The rotation taking body coordinates to the body's joint frame, in which its joint axis is z (so that
// S is [e_z; 0] or [0; e_z] for every joint): its rows are the frame's axes in body coordinates. A signed
// permutation (exact) for an axis ±x, ±y, ±z; the identity for a fixed joint.
Mat3 joint_frame(const Body& b) {
  Mat3 R = Mat3::Identity();
  if (b.joint == JointType::kFixed) return R;
  const Vec3& a = b.axis;
  for (int k = 0; k < 3; ++k) {
    const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    if (a[k1] == 0.0 && a[k2] == 0.0 && std::abs(a[k]) == 1.0) {
      R.setZero();
      R(0, a[k] > 0.0 ? k1 : k2) = 1.0;
      R(1, a[k] > 0.0 ? k2 : k1) = 1.0;
      R(2, k) = a[k];
      return R;
    }
  }
  int m = 0;  // z' = a, x' = the coordinate axis least along a made orthogonal to it, y' = z' × x'
  for (int k = 1; k < 3; ++k)
    if (std::abs(a[k]) < std::abs(a[m])) m = k;
  const Vec3 x = (Vec3::Unit(m) - a[m] * a).normalized();
  R.row(0) = x.transpose();
  R.row(1) = a.cross(x).transpose();
  R.row(2) = a.transpose();
  return R;
}

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
      double *Xt = blk(tl.X_tree, i, 12, W), *In = blk(tl.inertia, i, 10, W);
      const auto at = [W, l](int k) { return static_cast<std::size_t>(k) * W + l; };
      // In joint frames (R the body's, Rp its parent's, the base's the identity): X_tree' = rot(R) X_tree
      // rot(Rp)^T = rot(R E Rp^T) xlt(Rp r); the inertia's blocks R Ibar R^T, R h.
      const Mat3 R = joint_frame(b), Rp = b.parent < 0 ? Mat3::Identity() : joint_frame(t.body(b.parent));
      const Mat3 E = R * b.X_tree.E * Rp.transpose();
      const Vec3 r = Rp * b.X_tree.r;
      for (int r_ = 0; r_ < 3; ++r_)
        for (int c = 0; c < 3; ++c) Xt[at(3 * r_ + c)] = E(r_, c);
      for (int k = 0; k < 3; ++k) Xt[at(9 + k)] = r[k];
      const Mat3 Ibar = R * b.inertia.topLeftCorner<3, 3>() * R.transpose();
      const Vec3 h = R * (b.mass * b.com);
      In[at(0)] = b.mass;
      for (int k = 0; k < 3; ++k) In[at(1 + k)] = h[k];
      const double packed[6] = {Ibar(0, 0), Ibar(0, 1), Ibar(0, 2), Ibar(1, 1), Ibar(1, 2), Ibar(2, 2)};
      for (int k = 0; k < 6; ++k) In[at(4 + k)] = packed[k];
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
  c.assign(4 * n, 0.0);
  a.assign(6 * n, 0.0);
  IA.assign(21 * n, 0.0);
  pA.assign(6 * n, 0.0);
  d.assign(n, 1.0);
  u.assign(n, 0.0);
  zeros.assign(static_cast<std::size_t>(tl.nv) * tl.W, 0.0);
}

static void compute_tree_forward_dynamics_kernel(const TreeLanes& tl, const double* q, const double* qd,
                                                const double* tau, const double* extra_armature, double* qdd,
                                                TreeLanesWorkspace& ws) {
  if (ws.W != tl.W || ws.nb != tl.nb)
    throw std::invalid_argument("compute_tree_forward_dynamics: the workspace was made for another batch");
  const double* extra = extra_armature ? extra_armature : ws.zeros.data();
  switch (tl.W) {  // the usual widths with W known to the compiler (1.4x at W = 8), any other at run time
    case 4: aba_passes<4>(tl, q, qd, tau, extra, qdd, ws); break;
    case 8: aba_passes<8>(tl, q, qd, tau, extra, qdd, ws); break;
    case 16: aba_passes<16>(tl, q, qd, tau, extra, qdd, ws); break;
    default: aba_passes<0>(tl, q, qd, tau, extra, qdd, ws); break;
  }
}
// Compiled for AVX-512, AVX2 and SSE2, the active width's copy called (common/isa.hpp), the passes
// inlined into each so that their lane loops use its registers; the same bits at every width.
FF_ISA_DISPATCH(void, compute_tree_forward_dynamics,
                (const TreeLanes& tl, const double* q, const double* qd, const double* tau,
                 const double* extra_armature, double* qdd, TreeLanesWorkspace& ws),
                (tl, q, qd, tau, extra_armature, qdd, ws))

void compute_tree_passive_forces(const TreeLanes& tl, const double* q, const double* qd, const double* tau_applied,
                                 double* tau) {
  const std::size_t n = static_cast<std::size_t>(tl.nv) * tl.W;
  const double *k = tl.stiffness.data(), *c = tl.damping.data(), *q0 = tl.spring_reference.data();
#pragma omp simd
  for (std::size_t j = 0; j < n; ++j) {
    const double t = -k[j] * (q[j] - q0[j]) - c[j] * qd[j];
    tau[j] = tau_applied ? tau_applied[j] + t : t;
  }
  const std::size_t W = static_cast<std::size_t>(tl.W);
  for (std::size_t f = 0; f < tl.friction_dofs.size(); ++f) {
    const std::size_t o = static_cast<std::size_t>(tl.friction_dofs[f]) * W;
    const FrictionMap* fm = tl.friction.data() + f * W;
    for (std::size_t l = 0; l < W; ++l)
      if (is_friction_on(fm[l])) tau[o + l] += calc_friction_torque(at_angle(fm[l], q[o + l]), qd[o + l]);
  }
  // The nonlinear drive trains: the twist q_t = body - rotor, so the rotor drives the body with
  // T_t = T(-q_t, -qd_t) = -T(q_t, qd_t) (T odd); the body's coordinate is q_rotor + q_t, so the twist
  // gets T_t and the rotor, which feels T_t x factor (efficiency), T_t (1 - factor).
  for (std::size_t d = 0; d < tl.transmission_dofs.size(); ++d) {
    const std::size_t o = static_cast<std::size_t>(tl.transmission_dofs[d]) * W;
    const std::size_t r = static_cast<std::size_t>(tl.transmission_rotor_dofs[d]) * W;
    const LaneDrive* p = tl.transmissions.data() + d * W;
    for (std::size_t l = 0; l < W; ++l) {
      const double tt = -calc_transmission_torque(p[l], q[o + l], qd[o + l]);
      tau[o + l] += tt;
      if (p[l].eta != 1.0) tau[r + l] += tt * (1.0 - calc_efficiency_factor(p[l].eta, tt * qd[r + l]));
    }
  }
}

void set_tree_lanes_friction(TreeLanes& tl, int dof, std::span<const FrictionSpec> per_lane) {
  if (dof < 0 || dof >= tl.nv) throw std::invalid_argument("set_tree_lanes_friction: dof " + std::to_string(dof) + " out of range");
  if (per_lane.size() != static_cast<std::size_t>(tl.W))
    throw std::invalid_argument("set_tree_lanes_friction: " + std::to_string(per_lane.size()) + " maps for " +
                                std::to_string(tl.W) + " lanes");
  std::vector<FrictionMap> maps;
  bool on = false;
  for (std::size_t l = 0; l < per_lane.size(); ++l) {
    const FrictionSpec& f = per_lane[l];
    if (!(f.viscous >= 0.0) || !(f.coulomb >= 0.0) || !(f.stiction >= 0.0) ||
        (f.stiction > 0.0 && f.stiction < f.coulomb) || !(f.stribeck_velocity > 0.0) || !(f.smoothing > 0.0))
      throw std::invalid_argument("set_tree_lanes_friction: lane " + std::to_string(l) + ", dof " + std::to_string(dof) +
                                  ": not a physical friction map");
    maps.push_back(make_friction_map(f));
    on = on || is_friction_on(maps.back());
  }
  const std::size_t W = static_cast<std::size_t>(tl.W);
  const auto it = std::lower_bound(tl.friction_dofs.begin(), tl.friction_dofs.end(), dof);
  const std::size_t f = static_cast<std::size_t>(it - tl.friction_dofs.begin());
  const bool present = it != tl.friction_dofs.end() && *it == dof;
  if (present) {
    if (on) {
      std::copy(maps.begin(), maps.end(), tl.friction.begin() + static_cast<std::ptrdiff_t>(f * W));
    } else {
      tl.friction_dofs.erase(it);
      tl.friction.erase(tl.friction.begin() + static_cast<std::ptrdiff_t>(f * W),
                        tl.friction.begin() + static_cast<std::ptrdiff_t>((f + 1) * W));
    }
  } else if (on) {
    tl.friction_dofs.insert(it, dof);
    tl.friction.insert(tl.friction.begin() + static_cast<std::ptrdiff_t>(f * W), maps.begin(), maps.end());
  }
}

void add_tree_lanes_hydraulics(TreeLanes& tl, int dof, std::span<const LaneDrive> per_lane,
                               std::span<const double> load) {
  if (dof < 0 || dof >= tl.nv)
    throw std::invalid_argument("add_tree_lanes_hydraulics: dof " + std::to_string(dof) + " out of range");
  if (std::find(tl.hydraulic_dofs.begin(), tl.hydraulic_dofs.end(), dof) != tl.hydraulic_dofs.end())
    throw std::invalid_argument("add_tree_lanes_hydraulics: dof " + std::to_string(dof) + " has an actuator already");
  if (per_lane.size() != static_cast<std::size_t>(tl.W) || load.size() != static_cast<std::size_t>(tl.W))
    throw std::invalid_argument("add_tree_lanes_hydraulics: " + std::to_string(per_lane.size()) + " actuators and " +
                                std::to_string(load.size()) + " loads for " + std::to_string(tl.W) + " lanes");
  tl.hydraulic_dofs.push_back(dof);
  tl.hydraulics.insert(tl.hydraulics.end(), per_lane.begin(), per_lane.end());
  tl.hydraulic_load.insert(tl.hydraulic_load.end(), load.begin(), load.end());
}

TreeLanes extract_tree_lane(const TreeLanes& tl, int l) {
  if (l < 0 || l >= tl.W) throw std::invalid_argument("extract_tree_lane: lane " + std::to_string(l) + " out of range");
  const std::size_t W = static_cast<std::size_t>(tl.W), L = static_cast<std::size_t>(l);
  TreeLanes one = make_tree_lanes(std::span<const Tree>(&tl.trees[L], 1));
  // Every (rows x W) array's column l.
  const auto column = [&](const std::vector<double>& from, std::vector<double>& to) {
    to.resize(from.size() / W);
    for (std::size_t r = 0; r < to.size(); ++r) to[r] = from[r * W + L];
  };
  column(tl.armature, one.armature);
  column(tl.stiffness, one.stiffness);
  column(tl.damping, one.damping);
  column(tl.spring_reference, one.spring_reference);
  column(tl.gravity, one.gravity);
  column(tl.hydraulic_load, one.hydraulic_load);
  column(tl.bristle_stiffness, one.bristle_stiffness);
  column(tl.bristle_damping, one.bristle_damping);
  const auto laws = [&](const auto& from, auto& to) {
    to.clear();
    for (std::size_t r = 0; r < from.size() / W; ++r) to.push_back(from[r * W + L]);
  };
  laws(tl.friction, one.friction);
  laws(tl.hydraulics, one.hydraulics);
  laws(tl.lugre, one.lugre);
  laws(tl.transmissions, one.transmissions);
  one.friction_dofs = tl.friction_dofs;
  one.hydraulic_dofs = tl.hydraulic_dofs;
  one.lugre_dofs = tl.lugre_dofs;
  one.transmission_dofs = tl.transmission_dofs;
  one.transmission_rotor_dofs = tl.transmission_rotor_dofs;
  return one;
}

void add_tree_lanes_lugre(TreeLanes& tl, int dof, std::span<const FrictionSpec> per_lane) {
  const std::string me = "add_tree_lanes_lugre: dof " + std::to_string(dof);
  if (dof < 0 || dof >= tl.nv) throw std::invalid_argument(me + " out of range");
  if (std::find(tl.lugre_dofs.begin(), tl.lugre_dofs.end(), dof) != tl.lugre_dofs.end())
    throw std::invalid_argument(me + " has LuGre friction already");
  if (per_lane.size() != static_cast<std::size_t>(tl.W))
    throw std::invalid_argument(me + ": " + std::to_string(per_lane.size()) + " maps for " + std::to_string(tl.W) + " lanes");
  for (std::size_t l = 0; l < per_lane.size(); ++l) {
    const FrictionSpec& f = per_lane[l];
    if (!(f.viscous >= 0.0) || !(f.coulomb > 0.0) || !(f.stiction >= 0.0) || (f.stiction > 0.0 && f.stiction < f.coulomb) ||
        !(f.stribeck_velocity > 0.0) || !(f.bristle_stiffness > 0.0) || !(f.bristle_damping >= 0.0) ||
        !std::isfinite(f.bristle_stiffness) || !std::isfinite(f.bristle_damping))
      throw std::invalid_argument(me + ", lane " + std::to_string(l) + ": not a physical LuGre model");
  }
  set_tree_lanes_friction(tl, dof, std::vector<FrictionSpec>(per_lane.size()));  // no static map there
  tl.lugre_dofs.push_back(dof);
  for (const FrictionSpec& f : per_lane) {
    tl.lugre.push_back(make_friction_map(f));
    tl.bristle_stiffness.push_back(f.bristle_stiffness);
    tl.bristle_damping.push_back(f.bristle_damping);
  }
}

void add_tree_lanes_transmission(TreeLanes& tl, int twist, int rotor, std::span<const LaneDrive> per_lane) {
  const std::string me = "add_tree_lanes_transmission: twist dof " + std::to_string(twist);
  if (twist < 0 || twist >= tl.nv || rotor < 0 || rotor >= tl.nv || rotor == twist)
    throw std::invalid_argument(me + " or rotor dof " + std::to_string(rotor) + " out of range");
  if (std::find(tl.transmission_dofs.begin(), tl.transmission_dofs.end(), twist) != tl.transmission_dofs.end())
    throw std::invalid_argument(me + " has a drive train already");
  if (per_lane.size() != static_cast<std::size_t>(tl.W))
    throw std::invalid_argument(me + ": " + std::to_string(per_lane.size()) + " laws for " + std::to_string(tl.W) + " lanes");
  for (std::size_t l = 0; l < per_lane.size(); ++l) {
    const LaneDrive& p = per_lane[l];
    if (!(p.k > 0.0) || !(p.k3 >= 0.0) || !(p.c >= 0.0) || !(p.b >= 0.0) || !(p.eta > 0.0 && p.eta <= 1.0) ||
        !std::isfinite(p.k) || !std::isfinite(p.k3) || !std::isfinite(p.c) || !std::isfinite(p.b))
      throw std::invalid_argument(me + ", lane " + std::to_string(l) + ": not a physical drive train");
  }
  const std::size_t W = static_cast<std::size_t>(tl.W), o = static_cast<std::size_t>(twist) * W;
  std::fill_n(tl.stiffness.begin() + static_cast<std::ptrdiff_t>(o), W, 0.0);
  std::fill_n(tl.damping.begin() + static_cast<std::ptrdiff_t>(o), W, 0.0);
  tl.transmission_dofs.push_back(twist);
  tl.transmission_rotor_dofs.push_back(rotor);
  tl.transmissions.insert(tl.transmissions.end(), per_lane.begin(), per_lane.end());
}

void compute_tree_actuator_forces(const TreeLanes& tl, const double* q, const double* qd, const double* z,
                                  const double* tau_applied, double* tau_act, double* zdot) {
  const std::size_t W = static_cast<std::size_t>(tl.W), n = static_cast<std::size_t>(tl.nv) * W;
  if (tau_applied) std::copy(tau_applied, tau_applied + n, tau_act);
  else std::fill(tau_act, tau_act + n, 0.0);
  for (std::size_t a = 0; a < tl.hydraulic_dofs.size(); ++a) {
    const std::size_t o = static_cast<std::size_t>(tl.hydraulic_dofs[a]) * W, zo = kHydraulicStates * a * W;
    for (std::size_t l = 0; l < W; ++l) {
      const double cmd = tau_act[o + l];
      tau_act[o + l] = eval_hydraulic_actuator(tl.hydraulics[a * W + l], cmd, q[o + l], qd[o + l], z + zo + l, W,
                                               zdot ? zdot + zo + l : nullptr) -
                       tl.hydraulic_load[a * W + l];
    }
  }
  for (std::size_t b = 0; b < tl.lugre_dofs.size(); ++b) {
    const std::size_t o = static_cast<std::size_t>(tl.lugre_dofs[b]) * W;
    const std::size_t zo = static_cast<std::size_t>(tl.bristle_row(b)) * W;
    for (std::size_t l = 0; l < W; ++l) {
      const std::size_t i = b * W + l;
      const double w = qd[o + l], zb = z[zo + l];
      const FrictionMap f = at_angle(tl.lugre[i], q[o + l]);
      const double zd = calc_lugre_bristle_rate(f, tl.bristle_stiffness[i], w, zb);
      if (zdot) zdot[zo + l] = zd;
      tau_act[o + l] += calc_lugre_torque(f, tl.bristle_stiffness[i], tl.bristle_damping[i], w, zb, zd);
    }
  }
}

}  // namespace ff
