// Euler / matrix / quaternion / rot6D conversions.
#include "nec/motion/rotations.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nec {
namespace {


constexpr std::array<std::array<int, 3>, 6> kOrderAxes = {{
    {0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
constexpr std::array<std::string_view, 6> kOrderNames = {"XYZ", "XZY", "YXZ",
                                                         "YZX", "ZXY", "ZYX"};

}  // namespace

std::array<int, 3> euler_axes(EulerOrder order) {
  return kOrderAxes[static_cast<int>(order)];
}

std::string_view euler_order_name(EulerOrder order) {
  return kOrderNames[static_cast<int>(order)];
}

std::optional<EulerOrder> parse_euler_order(std::string_view name) {
  for (int i = 0; i < 6; ++i) {
    if (name == kOrderNames[i]) return static_cast<EulerOrder>(i);
  }
  return std::nullopt;
}

EulerOrder euler_order_from_axes(const std::array<int, 3>& axes) {
  for (int i = 0; i < 6; ++i) {
    if (kOrderAxes[i] == axes) return static_cast<EulerOrder>(i);
  }
  throw std::invalid_argument("euler_order_from_axes: not a permutation of X, Y, Z");
}

Quat axis_rotation(int axis, double degrees) {
  const double half = 0.5 * degrees / kDegreesPerRadian;
  Quat q(std::cos(half), 0.0, 0.0, 0.0);
  q.coeffs()[axis] = std::sin(half);  // coeffs() is (x, y, z, w)
  return q;
}

Quat euler_to_quat(const Vec3& degrees, EulerOrder order) {
  const auto axes = euler_axes(order);
  return axis_rotation(axes[0], degrees[0]) * axis_rotation(axes[1], degrees[1]) *
         axis_rotation(axes[2], degrees[2]);
}

Mat3 euler_to_matrix(const Vec3& degrees, EulerOrder order) {
  return euler_to_quat(degrees, order).toRotationMatrix();
}

// For R = R_a(t0) R_b(t1) R_c(t2) with (a, b, c) a permutation of the axes:
// R(a, c) = s * sin(t1) where s = +1 for a cyclic (a, b, c), -1 otherwise.
Vec3 matrix_to_euler(const Mat3& r, EulerOrder order) {
  const auto axes = euler_axes(order);
  const int a = axes[0], b = axes[1], c = axes[2];
  const double sign = ((b - a + 3) % 3 == 1) ? 1.0 : -1.0;
  const double s1 = std::clamp(sign * r(a, c), -1.0, 1.0);
  double t0, t1, t2;
  t1 = std::asin(s1);
  if (std::abs(s1) < 1.0 - 1e-12) {
    t0 = std::atan2(-sign * r(b, c), r(c, c));
    t2 = std::atan2(-sign * r(a, b), r(a, a));
  } else {
    // Gimbal lock: only t0 ± t2 is defined; put it all in t0.
    t2 = 0.0;
    t0 = std::atan2(sign * r(c, b), r(b, b));
  }
  return {t0 * kDegreesPerRadian, t1 * kDegreesPerRadian, t2 * kDegreesPerRadian};
}

Vec3 quat_to_euler(const Quat& q, EulerOrder order) {
  return matrix_to_euler(q.normalized().toRotationMatrix(), order);
}

Rot6 matrix_to_rot6d(const Mat3& r) {
  return {r(0, 0), r(1, 0), r(2, 0), r(0, 1), r(1, 1), r(2, 1)};
}

Mat3 rot6d_to_matrix(const Rot6& v) {
  Vec3 a(v[0], v[1], v[2]);
  Vec3 b(v[3], v[4], v[5]);
  const Vec3 x = a.normalized();
  const Vec3 y = (b - x.dot(b) * x).normalized();
  Mat3 r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = x.cross(y);
  return r;
}

double geodesic_distance(const Quat& a, const Quat& b) {
  // atan2 stays accurate for tiny angles, where acos of the dot product does not.
  const Quat relative = a.normalized().conjugate() * b.normalized();
  return 2.0 * std::atan2(relative.vec().norm(), std::abs(relative.w()));
}

Quat heading_rotation(const Quat& q) {
  const double norm = std::hypot(q.w(), q.y());
  if (norm < 1e-9) return Quat::Identity();
  return Quat(q.w() / norm, 0.0, q.y() / norm, 0.0);
}

double heading_angle(const Quat& q) {
  const Quat h = heading_rotation(q);
  return 2.0 * std::atan2(h.y(), h.w());
}

}  // namespace nec
