// Internal to zoo/: pi and degrees to radians, shared by the creature
// builders and motion synthesis.
#pragma once

namespace nec::zoo::detail {

constexpr double kPi = 3.14159265358979323846;
inline double radians(double degrees) { return degrees * kPi / 180.0; }

}  // namespace nec::zoo::detail
