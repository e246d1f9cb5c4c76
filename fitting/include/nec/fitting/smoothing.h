// Smoothing of per-frame signals, shared by the steps that correct a decoded
// motion against its source over time (heading, ground).
//
//   std::vector<double> slow = smooth_twice(difference, std::vector<double>(frames, 1.0), 31);
#pragma once

#include <vector>

namespace nec {

// Weighted least-squares line through the values of a centred window of `width` frames (odd), read at its
// centre: with equal weights the centred moving average inside the clip; near the ends, where the window is
// cut short, a trend is followed to the last frame instead of flattened. Weights must be positive and as
// many as the values.
std::vector<double> moving_line(const std::vector<double>& values, const std::vector<double>& weights, int width);

// moving_line applied twice: a smoother kernel (triangular inside the clip) with the same trend at the ends.
std::vector<double> smooth_twice(const std::vector<double>& values, const std::vector<double>& weights, int width);

// Odd window width in frames closest to `seconds` at `fps` (at least 1).
int odd_window_frames(double seconds, double fps);

}  // namespace nec
