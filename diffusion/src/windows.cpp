// Overlapping windows of a long motion.
#include "nec/diffusion/windows.h"

#include <torch/torch.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace nec::diffusion {

int64_t window_overlap(int64_t frames, int64_t overlap) {
  const int64_t chosen = overlap > 0 ? overlap : frames / 4;
  return std::clamp<int64_t>(chosen, 2, std::max<int64_t>(2, frames - 1));
}

std::vector<MotionWindow> layout_windows(const std::vector<int64_t>& segment_frames, int64_t max_frames, int64_t overlap) {
  if (segment_frames.empty()) throw std::invalid_argument("layout_windows: no segment");
  if (max_frames < 4) throw std::invalid_argument("layout_windows: max_frames must be >= 4");
  for (const int64_t frames : segment_frames) {
    if (frames < 1) throw std::invalid_argument("layout_windows: a segment of " + std::to_string(frames) + " frames");
  }
  const int64_t total = std::accumulate(segment_frames.begin(), segment_frames.end(), int64_t{0});
  // The segment holding each frame.
  std::vector<int> segment_of;
  for (size_t s = 0; s < segment_frames.size(); ++s) segment_of.insert(segment_of.end(), static_cast<size_t>(segment_frames[s]), static_cast<int>(s));
  if (segment_frames.size() == 1 && total <= max_frames) return {{0, total, 0}};

  int64_t frames = std::min(max_frames, total);
  if (segment_frames.size() > 1) {
    const int64_t shortest = *std::min_element(segment_frames.begin(), segment_frames.end());
    frames = std::min(frames, std::max<int64_t>(4, shortest + window_overlap(frames, overlap)));
  }
  const int64_t shared = window_overlap(frames, overlap);
  const int64_t stride = std::max<int64_t>(1, frames - shared);
  std::vector<MotionWindow> windows;
  for (int64_t start = 0;; start += stride) {
    const int64_t at = std::min(start, total - frames);
    windows.push_back({at, frames, segment_of[static_cast<size_t>(at + frames / 2)]});
    if (at + frames >= total) break;
  }
  return windows;
}

at::Tensor turn_horizontal(const at::Tensor& x, const at::Tensor& yaw) {
  const at::Tensor c = torch::cos(yaw).view({-1, 1}).to(x.scalar_type()), s = torch::sin(yaw).view({-1, 1}).to(x.scalar_type());
  const at::Tensor root = x.select(2, 0);  // (B, T, C)
  const at::Tensor dx = root.select(2, 0), dz = root.select(2, 2);
  at::Tensor turned_root = root.clone();
  turned_root.select(2, 0).copy_(c * dx + s * dz);
  turned_root.select(2, 2).copy_(-s * dx + c * dz);
  return torch::cat({turned_root.unsqueeze(2), x.narrow(2, 1, x.size(2) - 1)}, 2);
}

at::Tensor window_weights(int64_t frames, int64_t overlap, bool first, bool last) {
  at::Tensor weight = torch::ones({frames});
  auto w = weight.accessor<float, 1>();
  const double ramp = static_cast<double>(overlap);
  for (int64_t f = 0; f < frames; ++f) {
    if (!first && f < overlap) w[f] = std::min(w[f], static_cast<float>((f + 0.5) / ramp));
    if (!last && f >= frames - overlap) w[f] = std::min(w[f], static_cast<float>((frames - f - 0.5) / ramp));
  }
  return weight;
}

}  // namespace nec::diffusion
