// Smoothing of per-frame signals: moving least-squares lines.
#include "nec/fitting/smoothing.h"

#include <algorithm>
#include <cmath>

namespace nec {

std::vector<double> moving_line(const std::vector<double>& values, const std::vector<double>& weights, int width) {
  const int n = static_cast<int>(values.size()), half = width / 2;
  std::vector<double> out(values.size());
  for (int t = 0; t < n; ++t) {
    double w = 0.0, wx = 0.0, wxx = 0.0, wv = 0.0, wxv = 0.0;  // x: frames from t
    for (int u = std::max(0, t - half); u < std::min(n, t + half + 1); ++u) {
      const double x = u - t;
      w += weights[u];
      wx += weights[u] * x;
      wxx += weights[u] * x * x;
      wv += weights[u] * values[u];
      wxv += weights[u] * x * values[u];
    }
    const double mean_x = wx / w, mean_v = wv / w, spread = wxx - w * mean_x * mean_x;
    const double slope = spread > 1e-12 * w ? (wxv - w * mean_x * mean_v) / spread : 0.0;
    out[t] = mean_v - slope * mean_x;
  }
  return out;
}

std::vector<double> smooth_twice(const std::vector<double>& values, const std::vector<double>& weights, int width) {
  return moving_line(moving_line(values, weights, width), weights, width);
}

int odd_window_frames(double seconds, double fps) {
  return 2 * static_cast<int>(std::lround(0.5 * seconds * fps)) + 1;
}

}  // namespace nec
