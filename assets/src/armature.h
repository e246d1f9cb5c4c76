// The armature of an assimp scene: which nodes are joints, their rest pose,
// and the node transforms of any animation at any time. Shared by the reader
// (asset -> Clip) and the writer (Clip -> animation on the asset).
#pragma once

#include "nec/motion/rotations.h"

#include <assimp/scene.h>

#include <string>
#include <vector>

namespace nec::assets {

using Mat4 = Eigen::Matrix4d;

Mat4 to_eigen(const aiMatrix4x4& m);
aiMatrix4x4 to_assimp(const Mat4& m);
// The rotation of a matrix whose 3x3 part may carry scale (the nearest rotation).
Quat rotation_part(const Mat4& m);

struct SceneNode {
  const aiNode* node = nullptr;
  int parent = -1;       // index into Armature::nodes
  bool bone = false;     // deforms a mesh
  bool animated = false; // some animation has a channel for it
  bool moving = false;   // some animation changes its transform
};

struct Armature {
  std::vector<SceneNode> nodes;        // every scene node, parents first
  std::vector<int> joints;             // node index of each joint, parents first
  std::vector<int> joint_parents;      // (J) joint index of the parent, -1 for the root
  std::vector<int> end_site_joints;    // joint each end site hangs from
  std::vector<int> end_site_nodes;     // node of each end site
  std::vector<Mat4> own_world;         // every node's world transform without animation (file coordinates)
  std::vector<Mat4> rest;              // (J) world transform of each joint at rest (file coordinates)
  std::vector<Quat> rest_rotations;    // (J) rotation_part(rest[j])
  std::vector<Mat4> end_site_rest;     // world transform of each end site at rest
  Mat3 basis = Mat3::Identity();       // file axes -> nec's (+Y up, metres): x' = scale * basis * x
  double scale = 1.0;
  std::vector<std::string> warnings;

  int joint_count() const { return static_cast<int>(joints.size()); }
  std::string joint_name(int joint) const { return nodes[joints[joint]].node->mName.C_Str(); }
  // The world transform of the node above the root joint (identity when the root joint is the scene's root).
  Mat4 above_root() const {
    const int parent = nodes[joints[0]].parent;
    return parent < 0 ? Mat4(Mat4::Identity()) : own_world[parent];
  }
  // Where a world transform (file coordinates) puts its origin in nec's: metres, +Y up.
  Vec3 position(const Mat4& world) const { return scale * basis * world.topRightCorner<3, 1>(); }
};

// The joints' names as nec's Skeleton holds them: the node names, made non-empty and unique.
std::vector<std::string> joint_names(const Armature& armature);

// Throws InputError naming `path` when the scene has no armature.
Armature find_armature(const aiScene& scene, const std::string& path);

// The channel of `animation` that drives each node (nullptr where none; all
// nullptr for a null animation).
std::vector<const aiNodeAnim*> node_channels(const Armature& armature, const aiAnimation* animation);
// World transforms (file coordinates) of every node at `tick`, with `channels`
// from node_channels().
std::vector<Mat4> node_world_transforms(const Armature& armature, const std::vector<const aiNodeAnim*>& channels,
                                        double tick);

// The first and last key time of an animation, in ticks ({0, 0} without keys).
std::pair<double, double> key_range(const aiAnimation& animation);
double ticks_per_second(const aiAnimation& animation);

}  // namespace nec::assets
