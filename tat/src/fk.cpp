// Differentiable forward kinematics of Θ: rot6D, heading, root integration and
// the joint chain, in torch, matching motion/features.cpp and kinematics.cpp.
#include "nec/tat/fk.h"

#include <torch/torch.h>

#include <stdexcept>
#include <string>

namespace nec::tat {
namespace {

using torch::indexing::Slice;

// Squared norms below this count as zero (no direction): the result is then
// zero (rot6d) or the identity (heading) instead of NaN, with finite gradients.
constexpr double kTinySquaredNorm = 1e-20;

// v / |v| over the last dimension; zero stays zero.
at::Tensor normalized(const at::Tensor& v) {
  return v * (v * v).sum(-1, /*keepdim=*/true).clamp_min(kTinySquaredNorm).rsqrt();
}

void check_shape(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("features_to_positions: " + message);
}

}  // namespace

at::Tensor rot6d_to_matrix(const at::Tensor& rot6d) {
  if (rot6d.dim() < 1 || rot6d.size(-1) != 6) {
    throw std::invalid_argument("rot6d_to_matrix: last dimension must be 6, got shape " + std::to_string(rot6d.dim()) +
                                "-D with " + (rot6d.dim() ? std::to_string(rot6d.size(-1)) : "none"));
  }
  const at::Tensor a = rot6d.narrow(-1, 0, 3);
  const at::Tensor b = rot6d.narrow(-1, 3, 3);
  const at::Tensor x = normalized(a);
  const at::Tensor y = normalized(b - (x * b).sum(-1, /*keepdim=*/true) * x);
  const at::Tensor z = at::linalg_cross(x, y, /*dim=*/-1);
  return torch::stack({x, y, z}, /*dim=*/-1);  // columns
}

at::Tensor matrix_to_rot6d(const at::Tensor& matrix) {
  if (matrix.dim() < 2 || matrix.size(-1) != 3 || matrix.size(-2) != 3) {
    throw std::invalid_argument("matrix_to_rot6d: expected (..., 3, 3)");
  }
  return torch::cat({matrix.select(-1, 0), matrix.select(-1, 1)}, /*dim=*/-1);
}

at::Tensor heading_matrix(const at::Tensor& rotation) {
  if (rotation.dim() < 2 || rotation.size(-1) != 3 || rotation.size(-2) != 3) {
    throw std::invalid_argument("heading_matrix: expected (..., 3, 3)");
  }
  // With q = (w, x, y, z): R00 + R22 = 2 (w² - y²), R02 - R20 = 4 w y, whose
  // norm is 2 (w² + y²) = 1 + R11. Normalized, it is (cos θ, sin θ) of the
  // twist normalize(w, 0, y, 0) = rotation by θ about +Y. Unlike the
  // (1 + trace, R02 - R20) form, it stays defined when w = 0 but y != 0.
  const at::Tensor c = rotation.select(-1, 0).select(-1, 0) + rotation.select(-1, 2).select(-1, 2);
  const at::Tensor s = rotation.select(-2, 0).select(-1, 2) - rotation.select(-2, 2).select(-1, 0);
  const at::Tensor squared = c * c + s * s;
  const at::Tensor defined = squared > kTinySquaredNorm;
  const at::Tensor inverse = squared.clamp_min(kTinySquaredNorm).rsqrt();
  const at::Tensor cosine = torch::where(defined, c * inverse, torch::ones_like(c));
  const at::Tensor sine = torch::where(defined, s * inverse, torch::zeros_like(s));
  const at::Tensor zero = torch::zeros_like(c);
  const at::Tensor one = torch::ones_like(c);
  const at::Tensor rows = torch::stack({cosine, zero, sine, zero, one, zero, -sine, zero, cosine}, /*dim=*/-1);
  std::vector<int64_t> shape = rotation.sizes().vec();
  return rows.view(shape);
}

namespace {

// windows (N, L, J, 9) with each window's root orientations premultiplied by turn (N, 3, 3).
at::Tensor turn_root_orientations(const at::Tensor& windows, const at::Tensor& turn) {
  at::Tensor out = windows.clone();
  const at::Tensor root = rot6d_to_matrix(windows.select(2, 0).narrow(-1, 3, 6));  // (N, L, 3, 3)
  out.select(2, 0).narrow(-1, 3, 6).copy_(matrix_to_rot6d(torch::matmul(turn.unsqueeze(1), root)));
  return out;
}

// (N, L, J, 9) -> (N, 3, 3) heading of the root at frame `frame` of each window.
at::Tensor root_heading_at(const at::Tensor& windows, int64_t frame) {
  return heading_matrix(rot6d_to_matrix(windows.select(1, frame).select(1, 0).narrow(-1, 3, 6)));
}

}  // namespace

at::Tensor align_window_headings(const at::Tensor& windows) {
  if (windows.dim() != 4 || windows.size(3) != 9 || windows.size(0) == 0 || windows.size(1) == 0 ||
      windows.size(2) == 0) {
    throw std::invalid_argument("align_window_headings: windows must be (N > 0, L > 0, J > 0, 9)");
  }
  const at::Tensor headings = root_heading_at(windows, 0);  // (N, 3, 3)
  return turn_root_orientations(windows, torch::matmul(headings.narrow(0, 0, 1), headings.transpose(-1, -2)));
}

at::Tensor continue_window_headings(const at::Tensor& windows, const std::vector<int64_t>& starts) {
  if (windows.dim() != 4 || windows.size(3) != 9 || windows.size(2) == 0 ||
      static_cast<int64_t>(starts.size()) != windows.size(0)) {
    throw std::invalid_argument("continue_window_headings: windows must be (N, L, J > 0, 9) with N = starts.size()");
  }
  std::vector<at::Tensor> turned{windows.narrow(0, 0, std::min<int64_t>(1, windows.size(0)))};
  for (size_t k = 1; k < starts.size(); ++k) {
    const int64_t offset = starts[k] - starts[k - 1];
    if (offset <= 0 || offset > windows.size(1)) {
      throw std::invalid_argument("continue_window_headings: the windows must follow one another without gaps");
    }
    // Without overlap the window before ends one frame earlier: its last heading.
    const at::Tensor wanted = root_heading_at(turned.back(), std::min(offset, windows.size(1) - 1));  // (1, 3, 3)
    const at::Tensor window = windows.narrow(0, static_cast<int64_t>(k), 1);
    const at::Tensor has = root_heading_at(window, 0);                           // (1, 3, 3)
    turned.push_back(turn_root_orientations(window, torch::matmul(wanted, has.transpose(-1, -2))));
  }
  return torch::cat(turned);
}

FkResult features_to_positions(const at::Tensor& features, const at::Tensor& parents, const at::Tensor& offsets) {
  check_shape(features.dim() == 4 && features.size(3) == 9, "features must be (B, T, J, 9)");
  const int64_t batch = features.size(0), frames = features.size(1), joints = features.size(2);
  check_shape(parents.dim() == 2 && parents.size(0) == batch && parents.size(1) == joints,
              "parents must be (B, J) = (" + std::to_string(batch) + ", " + std::to_string(joints) + ")");
  check_shape(offsets.dim() == 3 && offsets.size(0) == batch && offsets.size(1) == joints && offsets.size(2) == 3,
              "offsets must be (B, J, 3) = (" + std::to_string(batch) + ", " + std::to_string(joints) + ", 3)");
  const auto options = features.options();

  const at::Tensor local = rot6d_to_matrix(features.narrow(-1, 3, 6));  // (B, T, J, 3, 3)
  if (joints == 0) return {features.new_zeros({batch, frames, 0, 3}), local};

  // Root trajectory: p_0 = H_0 Δ_0, p_t = p_{t-1} + H_t Δ_t.
  const at::Tensor root_rotation = local.select(2, 0);                                  // (B, T, 3, 3)
  const at::Tensor delta = features.select(2, 0).narrow(-1, 0, 3);                      // (B, T, 3)
  const at::Tensor world_delta = torch::matmul(heading_matrix(root_rotation), delta.unsqueeze(-1)).squeeze(-1);
  const at::Tensor root_position = world_delta.cumsum(/*dim=*/1);                       // (B, T, 3)

  // Local transforms (R, t) of every joint plus slot J, the identity that every
  // chain ends in. t is the rest offset, the trajectory for the root.
  const at::Tensor rest_offsets = offsets.to(options.dtype()).narrow(1, 1, joints - 1);  // (B, J - 1, 3)
  at::Tensor rotation = torch::cat({local, torch::eye(3, options).expand({batch, frames, 1, 3, 3})}, /*dim=*/2);
  at::Tensor translation = torch::cat({root_position.unsqueeze(2),
                                       rest_offsets.unsqueeze(1).expand({batch, frames, joints - 1, 3}),
                                       torch::zeros({batch, frames, 1, 3}, options)},
                                      /*dim=*/2);  // (B, T, J + 1, 3)

  // Pointer jumping: after step k, (rotation, translation)[j] composes the
  // chain of 2^k links ending at j, and ancestor[j] is the joint 2^k links up
  // (J: past the root). Composition is associative, so ceil(log2 J) steps give
  // the global transforms, each step two gathers and one batched product for
  // all joints at once. Padded joints (parent -1 beyond joint 0) hang from the
  // root with zero offset.
  at::Tensor ancestor = parents.to(torch::kLong).clone();
  ancestor.select(1, 0).fill_(joints);
  ancestor = torch::where(ancestor < 0, torch::zeros_like(ancestor), ancestor);
  ancestor = torch::cat({ancestor, torch::full({batch, 1}, joints, ancestor.options())}, /*dim=*/1);  // (B, J + 1)
  for (int64_t reach = 1; reach < joints; reach *= 2) {
    const at::Tensor index = ancestor.view({batch, 1, joints + 1, 1});
    const at::Tensor above_rotation = torch::gather(
        rotation, /*dim=*/2, index.unsqueeze(-1).expand({batch, frames, joints + 1, 3, 3}));
    const at::Tensor above_translation =
        torch::gather(translation, /*dim=*/2, index.expand({batch, frames, joints + 1, 3}));
    translation = above_translation + torch::matmul(above_rotation, translation.unsqueeze(-1)).squeeze(-1);
    rotation = torch::matmul(above_rotation, rotation);
    ancestor = torch::gather(ancestor, /*dim=*/1, ancestor);
  }

  FkResult result;
  result.positions = translation.narrow(2, 0, joints).contiguous();
  result.global_rotations = rotation.narrow(2, 0, joints).contiguous();
  return result;
}

}  // namespace nec::tat
