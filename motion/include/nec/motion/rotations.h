// Rotations: Euler angles in all six orders, matrices, unit quaternions and the
// 6D representation of Zhou et al. 2019, plus the geodesic distance.
//
//   Quat q = euler_to_quat({30, 10, -5}, EulerOrder::ZXY);   // degrees, BVH order
//   Vec3 zxy = quat_to_euler(q, EulerOrder::ZXY);             // back, same order
//   Rot6 r6 = matrix_to_rot6d(q.toRotationMatrix());
//
// Convention (as BVH): an order "ZXY" with angles (a, b, c) means
// R = Rz(a) * Rx(b) * Ry(c); angles are listed in the order's axis order.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace nec {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;
using Rot6 = std::array<double, 6>;  // first two columns of R: (r00, r10, r20, r01, r11, r21)

inline constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

enum class EulerOrder : unsigned char { XYZ, XZY, YXZ, YZX, ZXY, ZYX };

// Axis indices (0 = X, 1 = Y, 2 = Z) of an order, in application order.
std::array<int, 3> euler_axes(EulerOrder order);
// "XYZ".."ZYX"; parse_euler_order returns nullopt on anything else.
std::string_view euler_order_name(EulerOrder order);
std::optional<EulerOrder> parse_euler_order(std::string_view name);
// The order whose axes are `axes` (a permutation of 0, 1, 2).
EulerOrder euler_order_from_axes(const std::array<int, 3>& axes);

// Rotation by `degrees` about principal axis `axis` (0 = X, 1 = Y, 2 = Z).
Quat axis_rotation(int axis, double degrees);

// Angles in degrees, listed in the order's axis order.
Quat euler_to_quat(const Vec3& degrees, EulerOrder order);
Mat3 euler_to_matrix(const Vec3& degrees, EulerOrder order);
// Inverse of euler_to_matrix; the middle angle is in [-90, 90]. At gimbal lock
// the third angle is set to 0.
Vec3 matrix_to_euler(const Mat3& rotation, EulerOrder order);
Vec3 quat_to_euler(const Quat& rotation, EulerOrder order);

Rot6 matrix_to_rot6d(const Mat3& rotation);
// Gram–Schmidt on the two columns; any non-degenerate input gives a rotation.
Mat3 rot6d_to_matrix(const Rot6& rot6d);

// Angle in radians of the relative rotation between a and b, in [0, pi].
double geodesic_distance(const Quat& a, const Quat& b);

// Rotation about world +Y closest to q (swing–twist decomposition): the
// heading of an orientation. Identity when q has no defined heading.
Quat heading_rotation(const Quat& q);
// Heading angle (radians, about +Y) of heading_rotation(q).
double heading_angle(const Quat& q);

}  // namespace nec
