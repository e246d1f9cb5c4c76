// Long motions from a denoiser that reads at most max_frames at once (How to
// Move Your Dragon, section 7.2): overlapping windows, each with the caption
// of its segment, denoised together; at every step their x0 predictions are
// blended with weights that fall to 0 towards the window's inner edges.
//
//   std::vector<MotionWindow> windows = layout_windows({90, 60}, /*max_frames=*/120, /*overlap=*/0);
//   at::Tensor local = turn_horizontal(global.narrow(1, w.start, w.frames), yaw_at_start);  // window's own frame
//
// Why the turn: in model space the root's horizontal displacement is in the
// heading frame of the motion's frame 0 (tat/model_space.h), and a window is
// a motion of its own, trained as a crop: its frame is the heading at its
// start, yaw_s = ω_1 + … + ω_s turned from the motion's. So a window reads
// the global displacement turned by yaw_s, and its prediction is turned back
// by −yaw_s. Its frame 0 has no displacement or yaw rate of its own (a
// crop's first frame never moves): those channels get no weight there.
#pragma once

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <vector>

namespace nec::diffusion {

struct MotionWindow {
  int64_t start = 0;   // first frame in the whole motion
  int64_t frames = 0;  // length (the same for every window of a layout)
  int segment = 0;     // whose caption it reads: the segment holding its middle frame
};

// Windows over segments of the given lengths (frames, each >= 1) laid end to
// end. One window when everything fits in max_frames; else windows of
// max_frames (with several segments, at most the shortest segment plus the
// overlap, so that every segment holds some window's middle), neighbours
// sharing `overlap` frames (0: a quarter of the window), the last one ending
// at the end. std::invalid_argument for empty or non-positive lengths.
std::vector<MotionWindow> layout_windows(const std::vector<int64_t>& segment_frames, int64_t max_frames, int64_t overlap);

// The overlap layout_windows uses for windows of `frames` (0 asks for the default).
int64_t window_overlap(int64_t frames, int64_t overlap);

// Model space x (B, T, J, C) with the root's horizontal displacement (channels 0 and 2 of joint 0)
// turned by yaw (B) radians about +Y: (x, z) -> (cos·x + sin·z, −sin·x + cos·z).
at::Tensor turn_horizontal(const at::Tensor& x, const at::Tensor& yaw);

// (W) blend weights of a window's frames: ramps of `overlap` frames towards the sides that have a neighbour.
at::Tensor window_weights(int64_t frames, int64_t overlap, bool first, bool last);

}  // namespace nec::diffusion
