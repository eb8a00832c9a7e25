#include "multibody/lanes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "kernel/fastmath.hpp"

namespace ff {

namespace {

#define FF_INLINE [[gnu::always_inline]] inline
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FF_TARGET_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define FF_TARGET_CLONES
#endif

// The lane loops are written in scalar locals only (x0, x1, x2 for a 3-vector, M0..M8 for a 3x3
// row-major matrix, each a `double`): GCC vectorises a loop over lanes written so, and not one that
// keeps its small vectors in local arrays or structs. The macros below spell the 3-vector and 3x3
// operations on such names; each declares its result.
#define FF_V3(o, e0, e1, e2) [[maybe_unused]] double o##0 = (e0), o##1 = (e1), o##2 = (e2)
#define FF_LOAD3(o, base, k) FF_V3(o, base[(k) * sW + l], base[((k) + 1) * sW + l], base[((k) + 2) * sW + l])
#define FF_STORE3(base, k, v) \
  base[(k) * sW + l] = v##0, base[((k) + 1) * sW + l] = v##1, base[((k) + 2) * sW + l] = v##2
#define FF_CROSS(o, a, b) FF_V3(o, a##1 * b##2 - a##2 * b##1, a##2 * b##0 - a##0 * b##2, a##0 * b##1 - a##1 * b##0)
#define FF_DOT(a, b) (a##0 * b##0 + a##1 * b##1 + a##2 * b##2)
// o = M x and o = M^T x
#define FF_MV(o, M, x) \
  FF_V3(o, M##0 * x##0 + M##1 * x##1 + M##2 * x##2, M##3 * x##0 + M##4 * x##1 + M##5 * x##2, \
        M##6 * x##0 + M##7 * x##1 + M##8 * x##2)
#define FF_MTV(o, M, x) \
  FF_V3(o, M##0 * x##0 + M##3 * x##1 + M##6 * x##2, M##1 * x##0 + M##4 * x##1 + M##7 * x##2, \
        M##2 * x##0 + M##5 * x##1 + M##8 * x##2)
// 3x3 matrices: declare from nine values, load and store nine components, products A B, A^T B, A B^T.
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
#define FF_MMT(o, A, B) \
  FF_M3(o, A##0 * B##0 + A##1 * B##1 + A##2 * B##2, A##0 * B##3 + A##1 * B##4 + A##2 * B##5, \
        A##0 * B##6 + A##1 * B##7 + A##2 * B##8, A##3 * B##0 + A##4 * B##1 + A##5 * B##2, \
        A##3 * B##3 + A##4 * B##4 + A##5 * B##5, A##3 * B##6 + A##4 * B##7 + A##5 * B##8, \
        A##6 * B##0 + A##7 * B##1 + A##8 * B##2, A##6 * B##3 + A##7 * B##4 + A##8 * B##5, \
        A##6 * B##6 + A##7 * B##7 + A##8 * B##8)
// M -= x y^T s
#define FF_SUB_OUTER(M, x, y, s) \
  M##0 -= x##0 * s * y##0, M##1 -= x##0 * s * y##1, M##2 -= x##0 * s * y##2, M##3 -= x##1 * s * y##0, \
  M##4 -= x##1 * s * y##1, M##5 -= x##1 * s * y##2, M##6 -= x##2 * s * y##0, M##7 -= x##2 * s * y##1, \
  M##8 -= x##2 * s * y##2
// A symmetric 3x3 stored packed (xx, xy, xz, yy, yz, zz) at components k.. of a block, as a full M0..M8.
#define FF_LOAD_SYM(o, base, k)                                                                              \
  [[maybe_unused]] const double o##p0 = base[(k) * sW + l], o##p1 = base[((k) + 1) * sW + l], o##p2 = base[((k) + 2) * sW + l], \
               o##p3 = base[((k) + 3) * sW + l], o##p4 = base[((k) + 4) * sW + l],                            \
               o##p5 = base[((k) + 5) * sW + l];                                                              \
  FF_M3(o, o##p0, o##p1, o##p2, o##p1, o##p3, o##p4, o##p2, o##p4, o##p5)
#define FF_LOAD9(o, base, k)                                                                                  \
  FF_M3(o, base[(k) * sW + l], base[((k) + 1) * sW + l], base[((k) + 2) * sW + l], base[((k) + 3) * sW + l], \
        base[((k) + 4) * sW + l], base[((k) + 5) * sW + l], base[((k) + 6) * sW + l], base[((k) + 7) * sW + l], \
        base[((k) + 8) * sW + l])

// Component k of body i's K-vector block in lane l is at blk(v, i, K)[k * W + l].
FF_INLINE double* blk(std::vector<double>& v, int i, int K, std::size_t W) {
  return v.data() + static_cast<std::size_t>(i) * K * W;
}
FF_INLINE const double* blk(const std::vector<double>& v, int i, int K, std::size_t W) {
  return v.data() + static_cast<std::size_t>(i) * K * W;
}

// Pass 1 of the ABA for body i, root to tip, in every lane: the joint transform Xup = X_J(q) X_tree,
// the velocity v = Xup v_parent + S qd, c = v × S qd, and the rigid body's inertia and bias force
// p = v ×* I v as the start of the articulated quantities (RBDA Table 7.1, first loop).
template <JointType J, bool kRoot>
void aba_pass1(const TreeLanes& tl, int i, const double* q, const double* qd, TreeLanesWorkspace& ws) {
  const std::size_t sW = static_cast<std::size_t>(tl.W);
  const int W = tl.W, p = kRoot ? 0 : tl.parent[i], j = tl.dof[i] < 0 ? 0 : tl.dof[i];
  const double *axb = blk(tl.axis, i, 3, sW), *Xtb = blk(tl.X_tree, i, 12, sW), *Inb = blk(tl.inertia, i, 10, sW);
  const double* vpb = blk(ws.v, p, 6, sW);
  double *Xb = blk(ws.Xup, i, 12, sW), *vb = blk(ws.v, i, 6, sW), *cb = blk(ws.c, i, 6, sW);
  double *IAb = blk(ws.IA, i, 21, sW), *pAb = blk(ws.pA, i, 6, sW);
  const double *qj = q + j * sW, *qdj = qd + j * sW;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    FF_LOAD3(a, axb, 0);
    FF_LOAD9(Et, Xtb, 0);
    FF_LOAD3(r, Xtb, 9);
    // Joint transform. Revolute: E_J = R(a, q)^T = c 1 - s [a]× + (1 - c) a a^T (Rodrigues), r_J = 0;
    // prismatic: E_J = 1, r_J = a q. Composition: E = E_J E_tree, r = r_tree + E_tree^T r_J.
    FF_M3(E, Et0, Et1, Et2, Et3, Et4, Et5, Et6, Et7, Et8);
    double qdl = 0.0;
    if constexpr (J == JointType::kRevolute) {
      double s, co;
      calc_sincos(qj[l], s, co);
      const double t = 1.0 - co;
      FF_M3(EJ, co + t * a0 * a0, s * a2 + t * a0 * a1, -s * a1 + t * a0 * a2, -s * a2 + t * a1 * a0,
            co + t * a1 * a1, s * a0 + t * a1 * a2, s * a1 + t * a2 * a0, -s * a0 + t * a2 * a1, co + t * a2 * a2);
      FF_MM(En, EJ, Et);
      E0 = En0, E1 = En1, E2 = En2, E3 = En3, E4 = En4, E5 = En5, E6 = En6, E7 = En7, E8 = En8;
      qdl = qdj[l];
    } else if constexpr (J == JointType::kPrismatic) {
      const double ql = qj[l];
      FF_V3(rJ, a0 * ql, a1 * ql, a2 * ql);
      FF_MTV(dr, Et, rJ);
      r0 += dr0, r1 += dr1, r2 += dr2;
      qdl = qdj[l];
    }
    Xb[0 * sW + l] = E0, Xb[1 * sW + l] = E1, Xb[2 * sW + l] = E2, Xb[3 * sW + l] = E3, Xb[4 * sW + l] = E4;
    Xb[5 * sW + l] = E5, Xb[6 * sW + l] = E6, Xb[7 * sW + l] = E7, Xb[8 * sW + l] = E8;
    FF_STORE3(Xb, 9, r);
    // v = Xup v_parent + S qd: [E w; E (v - r × w)] (the base is at rest).
    FF_V3(w, 0.0, 0.0, 0.0);
    FF_V3(vl, 0.0, 0.0, 0.0);
    if constexpr (!kRoot) {
      FF_LOAD3(wp, vpb, 0);
      FF_CROSS(rw, r, wp);
      FF_V3(vr, vpb[3 * sW + l] - rw0, vpb[4 * sW + l] - rw1, vpb[5 * sW + l] - rw2);
      FF_MV(Ew, E, wp);
      FF_MV(Ev, E, vr);
      w0 = Ew0, w1 = Ew1, w2 = Ew2, vl0 = Ev0, vl1 = Ev1, vl2 = Ev2;
    }
    FF_V3(aq, a0 * qdl, a1 * qdl, a2 * qdl);  // the joint's rate along its axis
    FF_V3(cw, 0.0, 0.0, 0.0);
    FF_V3(cv, 0.0, 0.0, 0.0);
    if constexpr (J == JointType::kRevolute) {
      w0 += aq0, w1 += aq1, w2 += aq2;
      // c = v × [aq; 0] = [w × aq; vl × aq]
      FF_CROSS(x, w, aq);
      FF_CROSS(y, vl, aq);
      cw0 = x0, cw1 = x1, cw2 = x2, cv0 = y0, cv1 = y1, cv2 = y2;
    } else if constexpr (J == JointType::kPrismatic) {
      vl0 += aq0, vl1 += aq1, vl2 += aq2;
      // c = v × [0; aq] = [0; w × aq]
      FF_CROSS(y, w, aq);
      cv0 = y0, cv1 = y1, cv2 = y2;
    }
    FF_STORE3(vb, 0, w);
    FF_STORE3(vb, 3, vl);
    FF_STORE3(cb, 0, cw);
    FF_STORE3(cb, 3, cv);
    // The rigid inertia I = [Ibar, [h]×; [h]×^T, m 1] (RBDA eq. 2.63) and p = v ×* (I v):
    // I v = [Ibar w + h × vl; m vl - h × w],  v ×* [n; f] = [w × n + vl × f; w × f].
    const double m = Inb[0 * sW + l];
    FF_LOAD3(h, Inb, 1);
    FF_LOAD_SYM(Ib, Inb, 4);
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

// Pass 2 for body i, tip to root: U = I^A S, d = S^T U + armature, u = tau - S^T p^A; then the
// articulated inertia and bias force handed to the parent, I^a = I^A - U U^T / d and
// p^a = p^A + I^a c + U u / d, carried to its coordinates by X^T I^a X and X^T p^a (RBDA Table 7.1).
// X^T [A B; B^T C] X with X = rot(E) xlt(r): first A' = E^T A E (likewise B', C'), then
//   A'' = A' + r× B'^T - B' r× - r× C' r×,  B'' = B' + r× C',  C'' = C'.
template <JointType J, bool kRoot>
void aba_pass2(const TreeLanes& tl, int i, const double* tau, const double* extra, TreeLanesWorkspace& ws) {
  const std::size_t sW = static_cast<std::size_t>(tl.W);
  const int W = tl.W, p = kRoot ? 0 : tl.parent[i], j = tl.dof[i] < 0 ? 0 : tl.dof[i];
  const double* axb = blk(tl.axis, i, 3, sW);
  double *IAb = blk(ws.IA, i, 21, sW), *pAb = blk(ws.pA, i, 6, sW), *Ub = blk(ws.U, i, 6, sW);
  const double *cb = blk(ws.c, i, 6, sW), *Xb = blk(ws.Xup, i, 12, sW);
  double *IApb = blk(ws.IA, p, 21, sW), *pApb = blk(ws.pA, p, 6, sW);
  double* d = ws.d.data() + static_cast<std::size_t>(i) * sW;
  double* u = ws.u.data() + static_cast<std::size_t>(i) * sW;
  const double *arm = tl.armature.data() + j * sW, *xarm = extra + j * sW, *tj = tau + j * sW;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    FF_LOAD_SYM(A, IAb, 0);
    FF_LOAD9(B, IAb, 6);
    FF_LOAD_SYM(C, IAb, 15);
    FF_LOAD3(pt, pAb, 0);
    FF_LOAD3(pb, pAb, 3);
    if constexpr (J != JointType::kFixed) {
      FF_LOAD3(a, axb, 0);
      // U = [A a; B^T a] (revolute) or [B a; C a] (prismatic)
      FF_V3(Ut, 0.0, 0.0, 0.0);
      FF_V3(Uq, 0.0, 0.0, 0.0);
      double uj;
      if constexpr (J == JointType::kRevolute) {
        FF_MV(x, A, a);
        FF_MTV(y, B, a);
        Ut0 = x0, Ut1 = x1, Ut2 = x2, Uq0 = y0, Uq1 = y1, Uq2 = y2;
        d[l] = FF_DOT(a, Ut) + arm[l];
        uj = tj[l] - FF_DOT(a, pt);
      } else {
        FF_MV(x, B, a);
        FF_MV(y, C, a);
        Ut0 = x0, Ut1 = x1, Ut2 = x2, Uq0 = y0, Uq1 = y1, Uq2 = y2;
        d[l] = FF_DOT(a, Uq) + arm[l];
        uj = tj[l] - FF_DOT(a, pb);
      }
      d[l] += xarm[l];
      u[l] = uj;
      FF_STORE3(Ub, 0, Ut);
      FF_STORE3(Ub, 3, Uq);
      if constexpr (!kRoot) {
        const double dinv = 1.0 / d[l];
        FF_SUB_OUTER(A, Ut, Ut, dinv);
        FF_SUB_OUTER(B, Ut, Uq, dinv);
        FF_SUB_OUTER(C, Uq, Uq, dinv);
        // p^a = p^A + I^a c + U u / d
        FF_LOAD3(cw, cb, 0);
        FF_LOAD3(cv, cb, 3);
        FF_MV(t0, A, cw);
        FF_MV(t1, B, cv);
        FF_MTV(t2, B, cw);
        FF_MV(t3, C, cv);
        const double ud = uj * dinv;
        pt0 += t00 + t10 + Ut0 * ud, pt1 += t01 + t11 + Ut1 * ud, pt2 += t02 + t12 + Ut2 * ud;
        pb0 += t20 + t30 + Uq0 * ud, pb1 += t21 + t31 + Uq1 * ud, pb2 += t22 + t32 + Uq2 * ud;
      }
    }
    if constexpr (!kRoot) {
      FF_LOAD9(E, Xb, 0);
      FF_LOAD3(r, Xb, 9);
      FF_MM(AE, A, E);
      FF_MTM(A1, E, AE);
      FF_MM(BE, B, E);
      FF_MTM(B1, E, BE);
      FF_MM(CE, C, E);
      FF_MTM(C1, E, CE);
      FF_M3(R, 0.0, -r2, r1, r2, 0.0, -r0, -r1, r0, 0.0);
      FF_MM(RC, R, C1);
      FF_MMT(RBt, R, B1);
      FF_MM(BR, B1, R);
      FF_MM(RCR, RC, R);
      // Accumulate into the parent: packed A (entries 0, 1, 2, 4, 5, 8 of the full), full B, packed C.
      IApb[0 * sW + l] += A10 + RBt0 - BR0 - RCR0, IApb[1 * sW + l] += A11 + RBt1 - BR1 - RCR1;
      IApb[2 * sW + l] += A12 + RBt2 - BR2 - RCR2, IApb[3 * sW + l] += A14 + RBt4 - BR4 - RCR4;
      IApb[4 * sW + l] += A15 + RBt5 - BR5 - RCR5, IApb[5 * sW + l] += A18 + RBt8 - BR8 - RCR8;
      IApb[6 * sW + l] += B10 + RC0, IApb[7 * sW + l] += B11 + RC1, IApb[8 * sW + l] += B12 + RC2;
      IApb[9 * sW + l] += B13 + RC3, IApb[10 * sW + l] += B14 + RC4, IApb[11 * sW + l] += B15 + RC5;
      IApb[12 * sW + l] += B16 + RC6, IApb[13 * sW + l] += B17 + RC7, IApb[14 * sW + l] += B18 + RC8;
      IApb[15 * sW + l] += C10, IApb[16 * sW + l] += C11, IApb[17 * sW + l] += C12;
      IApb[18 * sW + l] += C14, IApb[19 * sW + l] += C15, IApb[20 * sW + l] += C18;
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
// qdd = (u - U . a) / d, a += S qdd.
template <JointType J, bool kRoot>
void aba_pass3(const TreeLanes& tl, int i, double* qdd, TreeLanesWorkspace& ws) {
  const std::size_t sW = static_cast<std::size_t>(tl.W);
  const int W = tl.W, p = kRoot ? 0 : tl.parent[i], j = tl.dof[i] < 0 ? 0 : tl.dof[i];
  const double *axb = blk(tl.axis, i, 3, sW), *Xb = blk(ws.Xup, i, 12, sW), *cb = blk(ws.c, i, 6, sW);
  const double *Ub = blk(ws.U, i, 6, sW), *apb = blk(ws.a, p, 6, sW), *gb = tl.gravity.data();
  double* ab = blk(ws.a, i, 6, sW);
  const double* d = ws.d.data() + static_cast<std::size_t>(i) * sW;
  const double* u = ws.u.data() + static_cast<std::size_t>(i) * sW;
  double* qj = qdd + j * sW;
#pragma omp simd
  for (int l = 0; l < W; ++l) {
    FF_LOAD9(E, Xb, 0);
    FF_LOAD3(r, Xb, 9);
    FF_V3(wp, 0.0, 0.0, 0.0);
    FF_V3(vp, 0.0, 0.0, 0.0);
    if constexpr (kRoot) {
      vp0 = -gb[0 * sW + l], vp1 = -gb[1 * sW + l], vp2 = -gb[2 * sW + l];
    } else {
      wp0 = apb[0 * sW + l], wp1 = apb[1 * sW + l], wp2 = apb[2 * sW + l];
      vp0 = apb[3 * sW + l], vp1 = apb[4 * sW + l], vp2 = apb[5 * sW + l];
    }
    FF_CROSS(rw, r, wp);
    FF_V3(vr, vp0 - rw0, vp1 - rw1, vp2 - rw2);
    FF_MV(aw, E, wp);
    FF_MV(av, E, vr);
    aw0 += cb[0 * sW + l], aw1 += cb[1 * sW + l], aw2 += cb[2 * sW + l];
    av0 += cb[3 * sW + l], av1 += cb[4 * sW + l], av2 += cb[5 * sW + l];
    if constexpr (J != JointType::kFixed) {
      FF_LOAD3(Ut, Ub, 0);
      FF_LOAD3(Uq, Ub, 3);
      const double x = (u[l] - (FF_DOT(Ut, aw) + FF_DOT(Uq, av))) / d[l];
      qj[l] = x;
      FF_LOAD3(a, axb, 0);
      if constexpr (J == JointType::kRevolute) {
        aw0 += a0 * x, aw1 += a1 * x, aw2 += a2 * x;
      } else {
        av0 += a0 * x, av1 += a1 * x, av2 += a2 * x;
      }
    }
    FF_STORE3(ab, 0, aw);
    FF_STORE3(ab, 3, av);
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
      double *ax = blk(tl.axis, i, 3, W), *Xt = blk(tl.X_tree, i, 12, W), *In = blk(tl.inertia, i, 10, W);
      const auto at = [W, l](int k) { return static_cast<std::size_t>(k) * W + l; };
      for (int k = 0; k < 3; ++k) ax[at(k)] = b.axis[k];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) Xt[at(3 * r + c)] = b.X_tree.E(r, c);
      for (int k = 0; k < 3; ++k) Xt[at(9 + k)] = b.X_tree.r[k];
      const Mat3 Ibar = b.inertia.topLeftCorner<3, 3>();
      const Vec3 h = b.mass * b.com;
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
  c.assign(6 * n, 0.0);
  a.assign(6 * n, 0.0);
  IA.assign(21 * n, 0.0);
  pA.assign(6 * n, 0.0);
  U.assign(6 * n, 0.0);
  d.assign(n, 1.0);
  u.assign(n, 0.0);
  zeros.assign(static_cast<std::size_t>(tl.nv) * tl.W, 0.0);
}

// Compiled for AVX-512, AVX2 and the baseline, the one the CPU has chosen at load time (GCC/clang
// function multiversioning), the passes inlined into each (flatten) so that their lane loops use its
// registers. The same bits on every path: the lanes never mix, and no multiply-add is fused
// (-ffp-contract=off), so each lane's operations are IEEE's, in the same order, at any width.
FF_TARGET_CLONES [[gnu::flatten]]
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
  const std::size_t W = static_cast<std::size_t>(tl.W);
  for (std::size_t f = 0; f < tl.friction_dofs.size(); ++f) {
    const std::size_t o = static_cast<std::size_t>(tl.friction_dofs[f]) * W;
    const FrictionMap* fm = tl.friction.data() + f * W;
    for (std::size_t l = 0; l < W; ++l)
      if (is_friction_on(fm[l])) tau[o + l] += calc_friction_torque(fm[l], qd[o + l]);
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
      const double zd = calc_lugre_bristle_rate(tl.lugre[i], tl.bristle_stiffness[i], w, zb);
      if (zdot) zdot[zo + l] = zd;
      tau_act[o + l] += calc_lugre_torque(tl.lugre[i], tl.bristle_stiffness[i], tl.bristle_damping[i], w, zb, zd);
    }
  }
}

}  // namespace ff
