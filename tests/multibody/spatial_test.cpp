// multibody/spatial: Plücker transforms, cross products and rigid-body inertias against their
// closed forms and the invariants of spatial algebra (Featherstone 2008, ch. 2).
#include "multibody/spatial.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/multibody/test_support.hpp"

namespace ff {
namespace {

constexpr double kPi = std::numbers::pi;

Transform random_transform(test::Rng& rng) { return Transform::from_pose(rng.rotation(), rng.vec3(-2.0, 2.0)); }

TEST(Spatial, RotationHelpersAreActiveProperRotations) {
  // rotz(pi/2) turns x onto y, roty(pi/2) z onto x, rotx(pi/2) y onto z.
  EXPECT_LT((rotz(kPi / 2) * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-15);
  EXPECT_LT((roty(kPi / 2) * Vec3::UnitZ() - Vec3::UnitX()).norm(), 1e-15);
  EXPECT_LT((rotx(kPi / 2) * Vec3::UnitY() - Vec3::UnitZ()).norm(), 1e-15);
  // axis_angle about the coordinate axes is rotx/roty/rotz; any axis gives R^T R = I, det R = 1,
  // and leaves its axis where it was.
  for (const double a : {-2.5, -0.3, 0.0, 0.7, 3.0}) {
    EXPECT_LT((axis_angle(Vec3::UnitX(), a) - rotx(a)).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((axis_angle(Vec3::UnitY(), a) - roty(a)).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((axis_angle(Vec3::UnitZ(), a) - rotz(a)).cwiseAbs().maxCoeff(), 1e-15);
  }
  test::Rng rng(11);
  for (int k = 0; k < 20; ++k) {
    const Vec3 axis = rng.unit();
    const Mat3 R = axis_angle(axis, rng.uniform(-kPi, kPi));
    EXPECT_LT((R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-15);
    EXPECT_LT((R * axis - axis).norm(), 1e-15);
  }
}

TEST(Spatial, ComposedTransformIsTheProductOfItsMatricesAndAppliesInSequence) {
  test::Rng rng(1);
  for (int k = 0; k < 20; ++k) {
    const Transform X_ba = random_transform(rng), X_cb = random_transform(rng);
    const Transform X_ca = X_cb * X_ba;
    EXPECT_LT((X_ca.matrix() - X_cb.matrix() * X_ba.matrix()).cwiseAbs().maxCoeff(), 1e-13);
    EXPECT_LT((X_ca.force_matrix() - X_cb.force_matrix() * X_ba.force_matrix()).cwiseAbs().maxCoeff(), 1e-13);
    const SpatialMotion m = rng.spatial(-1.0, 1.0);
    const SpatialForce f = rng.spatial(-1.0, 1.0);
    EXPECT_LT((X_ca.apply(m) - X_cb.apply(X_ba.apply(m))).norm(), 1e-14);
    EXPECT_LT((X_ca.apply_force(f) - X_cb.apply_force(X_ba.apply_force(f))).norm(), 1e-14);
    // A point: C's coordinates of a point given in A's.
    const Vec3 p = rng.vec3(-1.0, 1.0);
    EXPECT_LT((X_ca.apply_point(p) - X_cb.apply_point(X_ba.apply_point(p))).norm(), 1e-14);
  }
}

TEST(Spatial, InverseTransformUndoesTheTransform) {
  test::Rng rng(2);
  for (int k = 0; k < 20; ++k) {
    const Transform X = random_transform(rng);
    const Transform Xi = X.inverse();
    const Transform I = Xi * X;
    EXPECT_LT((I.E - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT(I.r.norm(), 1e-14);  // r up to 3.5 m
    EXPECT_LT((Xi.matrix() - X.matrix().inverse()).cwiseAbs().maxCoeff(), 1e-13);
    // X* = X^-T, and the apply_inverse* are the inverse's apply*.
    EXPECT_LT((X.force_matrix() - X.matrix().inverse().transpose()).cwiseAbs().maxCoeff(), 1e-13);
    const SpatialMotion m = rng.spatial(-1.0, 1.0);
    const SpatialForce f = rng.spatial(-1.0, 1.0);
    EXPECT_LT((X.apply_inverse(X.apply(m)) - m).norm(), 1e-14);
    EXPECT_LT((X.apply_inverse(m) - Xi.apply(m)).norm(), 1e-14);
    EXPECT_LT((X.apply_inverse_force(f) - X.matrix().transpose() * f).norm(), 1e-14);
    EXPECT_LT((X.apply_inverse_force(X.apply_force(f)) - f).norm(), 1e-14);
  }
}

TEST(Spatial, RotationAboutAnOffsetAxisHasVelocityOmegaCrossOffsetAtTheOrigin) {
  // A body spinning at omega about the axis through P = (0.4, -0.2, 0.3) m: in A's coordinates the
  // body-fixed point at A's origin moves at omega × (0 - P); in B (origin at P, turned 0.5 rad
  // about z) its linear part is zero and the angular part is omega in B's axes.
  const Vec3 P{0.4, -0.2, 0.3}, omega{0.0, 1.5, -2.0};
  SpatialMotion v_a;
  v_a << omega, omega.cross(-P);
  const Transform X_ba = Transform::from_pose(rotz(0.5), P);
  const SpatialMotion v_b = X_ba.apply(v_a);
  EXPECT_LT(v_b.tail<3>().norm(), 1e-15);
  EXPECT_LT((v_b.head<3>() - rotz(0.5).transpose() * omega).norm(), 1e-15);
}

TEST(Spatial, CrfIsMinusCrmTransposedAndBothMatchTheVectorProducts) {
  test::Rng rng(3);
  for (int k = 0; k < 20; ++k) {
    const SpatialMotion v = rng.spatial(-2.0, 2.0), m = rng.spatial(-2.0, 2.0);
    const SpatialForce f = rng.spatial(-2.0, 2.0);
    EXPECT_EQ(crf(v), SpatialMatrix(-crm(v).transpose()));
    EXPECT_LT((cross_motion(v, m) - crm(v) * m).norm(), 1e-14);
    EXPECT_LT((cross_force(v, f) - crf(v) * f).norm(), 1e-14);
    // v × v = 0, and (v × m) . f = -m . (v ×* f): the power identity behind crf = -crm^T.
    EXPECT_LT(cross_motion(v, v).norm(), 1e-15);
    EXPECT_NEAR(cross_motion(v, m).dot(f), -m.dot(cross_force(v, f)), 1e-13);
  }
}

TEST(Spatial, CrossProductsCommuteWithTransforms) {
  // X (v × m) = (X v) × (X m) and X* (v ×* f) = (X v) ×* (X* f).
  test::Rng rng(4);
  for (int k = 0; k < 20; ++k) {
    const Transform X = random_transform(rng);
    const SpatialMotion v = rng.spatial(-1.0, 1.0), m = rng.spatial(-1.0, 1.0);
    const SpatialForce f = rng.spatial(-1.0, 1.0);
    EXPECT_LT((X.apply(cross_motion(v, m)) - cross_motion(X.apply(v), X.apply(m))).norm(), 1e-13);
    EXPECT_LT((X.apply_force(cross_force(v, f)) - cross_force(X.apply(v), X.apply_force(f))).norm(), 1e-13);
  }
}

TEST(Spatial, TransformedForceDottedWithTransformedMotionConservesPower) {
  test::Rng rng(5);
  for (int k = 0; k < 50; ++k) {
    const Transform X = random_transform(rng);
    const SpatialMotion m = rng.spatial(-3.0, 3.0);
    const SpatialForce f = rng.spatial(-3.0, 3.0);
    const double power = f.dot(m);
    EXPECT_NEAR(X.apply_force(f).dot(X.apply(m)), power, 1e-12 * (1.0 + std::abs(power)));
    EXPECT_NEAR(X.apply_inverse_force(f).dot(X.apply_inverse(m)), power, 1e-12 * (1.0 + std::abs(power)));
  }
}

TEST(Spatial, PointMassInertiaGivesItsMomentumAndKineticEnergy) {
  // A 2 kg point at c: the top-left block is m (|c|² 1 - c c^T), momentum [c × m u; m u] and energy
  // m |u|² / 2 with u = v + omega × c the point's velocity.
  const double m = 2.0;
  const Vec3 c{0.3, -0.5, 0.8};
  const SpatialMatrix I = spatial_inertia(m, c, Mat3::Zero());
  const Mat3 J = m * (c.squaredNorm() * Mat3::Identity() - c * c.transpose());
  EXPECT_LT((I.topLeftCorner<3, 3>() - J).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(Mat3(I.bottomRightCorner<3, 3>()), Mat3(m * Mat3::Identity()));
  EXPECT_EQ(I, SpatialMatrix(I.transpose()));
  SpatialMotion v;
  v << 1.0, -2.0, 0.5, 0.2, 0.4, -0.7;
  const Vec3 u = v.tail<3>() + v.head<3>().cross(c);
  const SpatialForce h = I * v;
  EXPECT_LT((h.head<3>() - c.cross(m * u)).norm(), 1e-14);
  EXPECT_LT((h.tail<3>() - m * u).norm(), 1e-14);
  EXPECT_NEAR(0.5 * v.dot(I * v), 0.5 * m * u.squaredNorm(), 1e-14);
}

TEST(Spatial, UniformRodAboutItsEndHasMLSquaredOverThree) {
  // A 3 kg, 1.2 m uniform thin rod along x from the origin: I_c = diag(0, mL²/12, mL²/12) at
  // c = (L/2, 0, 0); about its end I_yy = I_zz = mL²/3, I_xx = 0, coupling block m c×.
  const double m = 3.0, L = 1.2;
  const Vec3 c{L / 2, 0.0, 0.0};
  const Mat3 Ic = Vec3(0.0, m * L * L / 12, m * L * L / 12).asDiagonal();
  const SpatialMatrix I = spatial_inertia(m, c, Ic);
  EXPECT_NEAR(I(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(I(1, 1), m * L * L / 3, 1e-14);
  EXPECT_NEAR(I(2, 2), m * L * L / 3, 1e-14);
  EXPECT_NEAR(I(1, 5), -m * L / 2, 1e-15);  // (m c×)_{yz} = -m c_x
  EXPECT_NEAR(I(2, 4), m * L / 2, 1e-15);   // (m c×)_{zy} = m c_x
  EXPECT_LT((I.topRightCorner<3, 3>() - m * skew(c)).cwiseAbs().maxCoeff(), 1e-15);
  // Spinning about z through the end at w: energy mL²w²/6, the end's linear momentum m w L/2 along y.
  const double w = 2.5;
  SpatialMotion v = SpatialMotion::Zero();
  v[2] = w;
  EXPECT_NEAR(0.5 * v.dot(I * v), m * L * L * w * w / 6, 1e-13);
  EXPECT_NEAR((I * v)[4], m * w * L / 2, 1e-14);
  // The inertia at the centre carried to the end by a transform is the same matrix.
  const SpatialMatrix I_centre = spatial_inertia(m, Vec3::Zero(), Ic);
  const Transform centre_X_end = Transform::translation(c);  // centre frame: origin at c in end coordinates
  EXPECT_LT((transform_inertia_to_parent(centre_X_end, I_centre) - I).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(Spatial, InertiaTransformKeepsKineticEnergy) {
  // 1/2 v_A . (A I) v_A = 1/2 (X v_A) . (B I) (X v_A) for a random body and transform X = B X_A.
  test::Rng rng(6);
  for (int k = 0; k < 20; ++k) {
    const double m = rng.uniform(0.5, 3.0);
    const SpatialMatrix I_b =
        spatial_inertia(m, rng.vec3(-0.5, 0.5), test::box_inertia(m, 0.2, 0.4, 0.3, rng.rotation()));
    const Transform X = random_transform(rng);
    const SpatialMatrix I_a = transform_inertia_to_parent(X, I_b);
    const SpatialMotion v = rng.spatial(-1.0, 1.0);
    EXPECT_NEAR(v.dot(I_a * v), X.apply(v).dot(I_b * X.apply(v)), 1e-12);
    EXPECT_LT((I_a - I_a.transpose()).cwiseAbs().maxCoeff(), 1e-13);
  }
}

}  // namespace
}  // namespace ff
