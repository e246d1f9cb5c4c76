// Rotations: Euler (all six orders) <-> matrix <-> quaternion <-> rot6D, geodesic distance.
#include "nec/motion/rotations.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>

namespace nec {
namespace {

constexpr EulerOrder kAllOrders[] = {EulerOrder::XYZ, EulerOrder::XZY, EulerOrder::YXZ,
                                     EulerOrder::YZX, EulerOrder::ZXY, EulerOrder::ZYX};

TEST(Rotations, EulerMatchesAxisAngleProduct) {
  // Reference: Eigen's AngleAxis product in the order's axis order.
  const Vec3 degrees(31.0, -47.0, 112.0);
  for (EulerOrder order : kAllOrders) {
    const auto axes = euler_axes(order);
    Mat3 expected = Mat3::Identity();
    for (int i = 0; i < 3; ++i) {
      expected = expected * Eigen::AngleAxisd(degrees[i] * M_PI / 180.0, Vec3::Unit(axes[i])).toRotationMatrix();
    }
    const double diff = (euler_to_matrix(degrees, order) - expected).cwiseAbs().maxCoeff();
    EXPECT_LT(diff, 1e-12) << euler_order_name(order);
  }
}

TEST(Rotations, EulerRoundTripAllOrdersRandom) {
  std::mt19937 rng(7);
  double worst = 0.0;
  for (EulerOrder order : kAllOrders) {
    for (int i = 0; i < 2000; ++i) {
      const Quat q = testing::random_rotation(rng);
      const Vec3 e = quat_to_euler(q, order);
      EXPECT_LE(std::abs(e[1]), 90.0 + 1e-9);
      worst = std::max(worst, geodesic_distance(q, euler_to_quat(e, order)));
    }
  }
  EXPECT_LT(worst, 1e-9) << "largest geodesic error (rad): " << worst;
}

TEST(Rotations, GimbalLockStillReconstructs) {
  for (EulerOrder order : kAllOrders) {
    for (double middle : {90.0, -90.0}) {
      const Quat q = euler_to_quat(Vec3(25.0, middle, -40.0), order);
      const Vec3 e = quat_to_euler(q, order);
      EXPECT_LT(geodesic_distance(q, euler_to_quat(e, order)), 1e-6) << euler_order_name(order) << " " << middle;
    }
  }
}

TEST(Rotations, KnownValues) {
  // 90 degrees about Z maps +X to +Y.
  const Vec3 v = euler_to_quat(Vec3(90.0, 0.0, 0.0), EulerOrder::ZXY) * Vec3::UnitX();
  EXPECT_NEAR((v - Vec3::UnitY()).norm(), 0.0, 1e-12);
  // Intrinsic order: ZXY applies Y first to a vector.
  const Vec3 w = euler_to_quat(Vec3(90.0, 0.0, 90.0), EulerOrder::ZXY) * Vec3::UnitZ();
  // Ry(90) z = x, then Rz(90) x = y.
  EXPECT_NEAR((w - Vec3::UnitY()).norm(), 0.0, 1e-12);
}

TEST(Rotations, Rot6dRoundTripAndOrthonormalisation) {
  std::mt19937 rng(3);
  for (int i = 0; i < 500; ++i) {
    const Mat3 r = testing::random_rotation(rng).toRotationMatrix();
    EXPECT_LT((rot6d_to_matrix(matrix_to_rot6d(r)) - r).cwiseAbs().maxCoeff(), 1e-12);
  }
  // Non-orthogonal input still gives a proper rotation.
  const Mat3 m = rot6d_to_matrix({2.0, 0.1, 0.0, 0.3, 1.0, 0.2});
  EXPECT_LT((m.transpose() * m - Mat3::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(m.determinant(), 1.0, 1e-12);
}

TEST(Rotations, GeodesicDistance) {
  const Quat a = euler_to_quat(Vec3(0.0, 0.0, 0.0), EulerOrder::XYZ);
  const Quat b = euler_to_quat(Vec3(0.0, 0.0, 60.0), EulerOrder::XYZ);
  EXPECT_NEAR(geodesic_distance(a, b), M_PI / 3.0, 1e-12);
  // q and -q are the same rotation.
  EXPECT_NEAR(geodesic_distance(b, Quat(-b.coeffs())), 0.0, 1e-7);
  EXPECT_NEAR(geodesic_distance(a, euler_to_quat(Vec3(180.0, 0, 0), EulerOrder::XYZ)), M_PI, 1e-7);
}

TEST(Rotations, HeadingIsEquivariantToYaw) {
  std::mt19937 rng(11);
  for (int i = 0; i < 200; ++i) {
    const Quat q = testing::random_rotation(rng);
    const Quat yaw = axis_rotation(1, 73.0);
    const Quat lhs = heading_rotation(yaw * q);
    const Quat rhs = yaw * heading_rotation(q);
    EXPECT_LT(geodesic_distance(lhs, rhs), 1e-9);
    EXPECT_NEAR(lhs.x(), 0.0, 1e-12);
    EXPECT_NEAR(lhs.z(), 0.0, 1e-12);
  }
  EXPECT_NEAR(heading_angle(axis_rotation(1, 30.0)), M_PI / 6.0, 1e-12);
}

TEST(Rotations, OrderNames) {
  for (EulerOrder order : kAllOrders) EXPECT_EQ(parse_euler_order(euler_order_name(order)), order);
  EXPECT_FALSE(parse_euler_order("XXY").has_value());
}

}  // namespace
}  // namespace nec
