// Skeleton -> graph tensors, and padded batches of graphs.
#include "nec/owo/graph.h"

#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::owo {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

JointRelation relation(const Skeleton& skeleton, int i, int j, int lca) {
  if (i == j) return JointRelation::Self;
  if (skeleton.parents[j] == i) return JointRelation::Parent;
  if (skeleton.parents[i] == j) return JointRelation::Child;
  if (lca == i) return JointRelation::Ancestor;
  if (lca == j) return JointRelation::Descendant;
  return JointRelation::Other;
}

// Pads `value` (shape (J, ...)) along dims 0 (and 1 when `square`) to `size`.
at::Tensor pad_joints(const at::Tensor& value, int64_t size, bool square, double fill) {
  std::vector<int64_t> shape = value.sizes().vec();
  shape[0] = size;
  if (square) shape[1] = size;
  at::Tensor out = torch::full(shape, fill, value.options());
  const int64_t j = value.size(0);
  if (square) {
    out.narrow(0, 0, j).narrow(1, 0, j).copy_(value);
  } else {
    out.narrow(0, 0, j).copy_(value);
  }
  return out;
}

}  // namespace

void visit_fields(train::ConfigVisitor& v, GraphOptions& c) {
  v.field("normalize_scale", c.normalize_scale, "divide offsets and positions by the skeleton's diameter");
  v.field("position_frequencies", c.position_frequencies, "sinusoidal bands per coordinate of a relative position");
  v.field("depth_scale", c.depth_scale, "node feature = tree depth x depth_scale");
  v.field("children_scale", c.children_scale, "node feature = child count x children_scale");
  v.field("max_tree_distance", c.max_tree_distance, "tree distances are clipped here before scaling to [0, 1]");
}

void GraphOptions::validate() const {
  require(position_frequencies >= 0 && position_frequencies <= 16,
          "GraphOptions: position_frequencies must be in [0, 16], got " + std::to_string(position_frequencies));
  require(depth_scale > 0.0, "GraphOptions: depth_scale must be positive");
  require(children_scale > 0.0, "GraphOptions: children_scale must be positive");
  require(max_tree_distance >= 1, "GraphOptions: max_tree_distance must be at least 1");
}

int edge_feature_width(const GraphOptions& options) {
  return 3 * (1 + 2 * options.position_frequencies) + 1 + kJointRelationCount;
}

SkeletonGraph make_skeleton_graph(const Skeleton& skeleton, const at::Tensor& name_embeddings,
                                  const GraphOptions& options) {
  options.validate();
  skeleton.validate();
  const int count = skeleton.joint_count();
  require(count >= 1, "make_skeleton_graph: the skeleton has no joints");
  if (name_embeddings.defined()) {
    require(name_embeddings.dim() == 2 && name_embeddings.size(0) == count,
            "make_skeleton_graph: name_embeddings must be (J, E) with J = " + std::to_string(count) +
                ", got " + std::to_string(name_embeddings.dim()) + " dims, first " +
                (name_embeddings.dim() > 0 ? std::to_string(name_embeddings.size(0)) : std::string("-")));
  }
  const double diameter = skeleton.diameter();
  const double scale = options.normalize_scale && diameter > 0.0 ? 1.0 / diameter : 1.0;

  std::vector<Vec3> offsets(count, Vec3::Zero());  // root: 0
  std::vector<Vec3> positions(count, Vec3::Zero());
  std::vector<int> depths(count, 0);
  std::vector<int> child_counts(count, 0);
  for (int j = 1; j < count; ++j) {
    const int parent = skeleton.parents[j];
    offsets[j] = skeleton.offsets[j] * scale;
    positions[j] = positions[parent] + offsets[j];
    depths[j] = depths[parent] + 1;
    ++child_counts[parent];
  }

  SkeletonGraph graph;
  graph.joint_count = count;
  const auto f32 = torch::TensorOptions().dtype(torch::kFloat32);
  const auto i64 = torch::TensorOptions().dtype(torch::kInt64);
  graph.node_geometry = torch::zeros({count, kNodeGeometryWidth}, f32);
  graph.rest_offsets = torch::zeros({count, 3}, f32);
  graph.rest_positions = torch::zeros({count, 3}, f32);
  graph.parents = torch::zeros({count}, i64);
  graph.depths = torch::zeros({count}, i64);
  auto node = graph.node_geometry.accessor<float, 2>();
  auto offset_out = graph.rest_offsets.accessor<float, 2>();
  auto position_out = graph.rest_positions.accessor<float, 2>();
  auto parent_out = graph.parents.accessor<int64_t, 1>();
  auto depth_out = graph.depths.accessor<int64_t, 1>();
  for (int j = 0; j < count; ++j) {
    for (int c = 0; c < 3; ++c) {
      offset_out[j][c] = static_cast<float>(offsets[j][c]);
      position_out[j][c] = static_cast<float>(positions[j][c]);
      node[j][c] = static_cast<float>(offsets[j][c]);
    }
    node[j][3] = static_cast<float>(offsets[j].norm());
    node[j][4] = static_cast<float>(depths[j] * options.depth_scale);
    node[j][5] = static_cast<float>(child_counts[j] * options.children_scale);
    node[j][6] = child_counts[j] == 0 ? 1.0f : 0.0f;
    parent_out[j] = skeleton.parents[j];
    depth_out[j] = depths[j];
  }

  const int frequencies = options.position_frequencies;
  const int width = edge_feature_width(options);
  graph.tree_distance = torch::zeros({count, count}, i64);
  graph.lca = torch::zeros({count, count}, i64);
  graph.edge_features = torch::zeros({count, count, width}, f32);
  auto distance_out = graph.tree_distance.accessor<int64_t, 2>();
  auto lca_out = graph.lca.accessor<int64_t, 2>();
  auto edge = graph.edge_features.accessor<float, 3>();
  for (int i = 0; i < count; ++i) {
    for (int j = 0; j < count; ++j) {
      const int lca = skeleton.lowest_common_ancestor(i, j);
      const int distance = depths[i] + depths[j] - 2 * depths[lca];
      lca_out[i][j] = lca;
      distance_out[i][j] = distance;
      const Vec3 relative = positions[j] - positions[i];
      int f = 0;
      for (int c = 0; c < 3; ++c) {
        edge[i][j][f++] = static_cast<float>(relative[c]);
        for (int k = 0; k < frequencies; ++k) {
          const double angle = std::ldexp(kPi, k) * relative[c];
          edge[i][j][f++] = static_cast<float>(std::sin(angle));
          edge[i][j][f++] = static_cast<float>(std::cos(angle));
        }
      }
      edge[i][j][f++] =
          static_cast<float>(std::min(distance, options.max_tree_distance)) / options.max_tree_distance;
      edge[i][j][f + static_cast<int>(relation(skeleton, i, j, lca))] = 1.0f;
    }
  }
  if (name_embeddings.defined()) graph.name_embeddings = name_embeddings.detach().to(torch::kCPU, torch::kFloat32);
  return graph;
}

int64_t GraphBatch::size() const { return joint_mask.size(0); }
int64_t GraphBatch::max_joints() const { return joint_mask.size(1); }

GraphBatch GraphBatch::to(const c10::Device& device) const {
  GraphBatch out;
  out.joint_mask = joint_mask.to(device);
  out.has_names = has_names.to(device);
  out.joint_counts = joint_counts.to(device);
  out.node_geometry = node_geometry.to(device);
  out.name_embeddings = name_embeddings.to(device);
  out.rest_offsets = rest_offsets.to(device);
  out.rest_positions = rest_positions.to(device);
  out.parents = parents.to(device);
  out.depths = depths.to(device);
  out.tree_distance = tree_distance.to(device);
  out.lca = lca.to(device);
  out.edge_features = edge_features.to(device);
  return out;
}

GraphBatch collate(const std::vector<SkeletonGraph>& graphs, int64_t name_dim) {
  require(!graphs.empty(), "collate: no graphs");
  require(name_dim >= 0, "collate: name_dim must be >= 0");
  int64_t max_joints = 0;
  for (const SkeletonGraph& graph : graphs) max_joints = std::max(max_joints, graph.joint_count);

  std::vector<at::Tensor> mask, has_names, counts, geometry, names, offsets, positions, parents, depths, distance,
      lca, edges;
  for (size_t b = 0; b < graphs.size(); ++b) {
    const SkeletonGraph& graph = graphs[b];
    const int64_t count = graph.joint_count;
    at::Tensor name_rows;
    if (graph.name_embeddings.defined()) {
      require(graph.name_embeddings.size(1) == name_dim,
              "collate: graph " + std::to_string(b) + " has name embeddings of width " +
                  std::to_string(graph.name_embeddings.size(1)) + ", expected name_dim = " + std::to_string(name_dim));
      name_rows = graph.name_embeddings;
    } else {
      name_rows = torch::zeros({count, name_dim}, torch::kFloat32);
    }
    mask.push_back(torch::arange(max_joints, torch::kInt64) < count);
    has_names.push_back(torch::tensor(graph.name_embeddings.defined(), torch::kBool));
    counts.push_back(torch::tensor(count, torch::kInt64));
    geometry.push_back(pad_joints(graph.node_geometry, max_joints, false, 0.0));
    names.push_back(pad_joints(name_rows, max_joints, false, 0.0));
    offsets.push_back(pad_joints(graph.rest_offsets, max_joints, false, 0.0));
    positions.push_back(pad_joints(graph.rest_positions, max_joints, false, 0.0));
    parents.push_back(pad_joints(graph.parents, max_joints, false, -1.0));
    depths.push_back(pad_joints(graph.depths, max_joints, false, 0.0));
    distance.push_back(pad_joints(graph.tree_distance, max_joints, true, 0.0));
    lca.push_back(pad_joints(graph.lca, max_joints, true, -1.0));
    edges.push_back(pad_joints(graph.edge_features, max_joints, true, 0.0));
  }
  GraphBatch out;
  out.joint_mask = torch::stack(mask);
  out.has_names = torch::stack(has_names);
  out.joint_counts = torch::stack(counts);
  out.node_geometry = torch::stack(geometry);
  out.name_embeddings = torch::stack(names);
  out.rest_offsets = torch::stack(offsets);
  out.rest_positions = torch::stack(positions);
  out.parents = torch::stack(parents);
  out.depths = torch::stack(depths);
  out.tree_distance = torch::stack(distance);
  out.lca = torch::stack(lca);
  out.edge_features = torch::stack(edges);
  return out;
}

}  // namespace nec::owo
