// Skeleton graph featurization (no learning): what the OwO graph encoder sees
// of a rest-pose skeleton (NECromancer appendix C.2.1-C.2.4), and batches of
// several skeletons padded to the largest one.
//
//   SkeletonGraph dog = make_skeleton_graph(dog_skeleton, dog_name_vectors);  // (J, E) or {}
//   SkeletonGraph cat = make_skeleton_graph(cat_skeleton);                    // names: zeros
//   GraphBatch batch = collate({dog, cat}, /*name_dim=*/E);
//   // batch.joint_mask (B, Jmax), batch.edge_features (B, Jmax, Jmax, F), batch.lca (B, Jmax, Jmax) ...
//
// Geometry is root-relative (the root's own offset, its placement in the
// world, is dropped) and divided by the skeleton's diameter when
// GraphOptions::normalize_scale is set, so a rig in centimetres and the same
// rig in metres give the same graph.
#pragma once

#include "nec/motion/skeleton.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <vector>

namespace nec::train {
class ConfigVisitor;
}

namespace nec::owo {

// Featurization settings; saved with a model (they fix the input widths).
struct GraphOptions {
  bool normalize_scale = true;    // divide offsets and positions by Skeleton::diameter()
  int position_frequencies = 4;   // sinusoidal bands per coordinate of a relative position, e.g. 4
  double depth_scale = 0.1;       // node feature = depth * depth_scale (depths reach ~40 in snakes)
  double children_scale = 0.25;   // node feature = child count * children_scale
  int max_tree_distance = 16;     // tree distances are clipped here before scaling to [0, 1]

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, GraphOptions& c);  // train/config_fields.h

// Relation of joint i to joint j, one-hot in the edge features (in this order).
enum class JointRelation : int { Self, Parent, Child, Ancestor, Descendant, Other };
constexpr int kJointRelationCount = 6;

// Per-joint geometric input width: offset xyz, bone length, scaled depth,
// scaled child count, leaf flag.
constexpr int kNodeGeometryWidth = 7;
// Per-pair input width: [x, sin(2^k pi x), cos(2^k pi x)] per coordinate of
// p_j - p_i, the scaled tree distance, and the relation one-hot.
int edge_feature_width(const GraphOptions& options);

// One skeleton as tensors (CPU). J = joint count, F = edge_feature_width.
struct SkeletonGraph {
  int64_t joint_count = 0;
  at::Tensor node_geometry;    // (J, 7) float32, see kNodeGeometryWidth
  at::Tensor name_embeddings;  // (J, E) float32, caller's name vectors; undefined when none given
  at::Tensor rest_offsets;     // (J, 3) float32 offset from the parent (root: 0), normalized
  at::Tensor rest_positions;   // (J, 3) float32 rest position relative to the root, normalized
  at::Tensor parents;          // (J) int64, -1 for the root
  at::Tensor depths;           // (J) int64, root 0
  at::Tensor tree_distance;    // (J, J) int64, bones on the path from i to j
  at::Tensor lca;              // (J, J) int64, lowest common ancestor of i and j
  at::Tensor edge_features;    // (J, J, F) float32, features of the edge i -> j
};

// `name_embeddings`, when defined, must be (J, E) float: one row per joint.
// Throws std::invalid_argument for an invalid skeleton or mismatched names.
SkeletonGraph make_skeleton_graph(const Skeleton& skeleton, const at::Tensor& name_embeddings = {},
                                  const GraphOptions& options = {});

// Several skeletons padded to Jmax joints; padding is zero (parents, lca: -1).
struct GraphBatch {
  at::Tensor joint_mask;       // (B, Jmax) bool, true for real joints
  at::Tensor has_names;        // (B) bool, true where the caller gave name embeddings
  at::Tensor joint_counts;     // (B) int64
  at::Tensor node_geometry;    // (B, Jmax, 7) float32
  at::Tensor name_embeddings;  // (B, Jmax, E) float32, zeros where absent
  at::Tensor rest_offsets;     // (B, Jmax, 3) float32
  at::Tensor rest_positions;   // (B, Jmax, 3) float32
  at::Tensor parents;          // (B, Jmax) int64, -1 for roots and padding
  at::Tensor depths;           // (B, Jmax) int64
  at::Tensor tree_distance;    // (B, Jmax, Jmax) int64
  at::Tensor lca;              // (B, Jmax, Jmax) int64, -1 where i or j is padding
  at::Tensor edge_features;    // (B, Jmax, Jmax, F) float32

  int64_t size() const;        // B
  int64_t max_joints() const;  // Jmax
  GraphBatch to(const c10::Device& device) const;
};

// Graphs without names get zero rows of width `name_dim`; graphs with names
// must have exactly `name_dim` columns. Throws std::invalid_argument otherwise
// or when `graphs` is empty.
GraphBatch collate(const std::vector<SkeletonGraph>& graphs, int64_t name_dim);

}  // namespace nec::owo
