// Finding the armature in an assimp scene and evaluating its animations.
#include "armature.h"

#include "nec/motion/error.h"

#include <Eigen/SVD>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string_view>

namespace nec::assets {
namespace {

void flatten(const aiNode* node, int parent, std::vector<SceneNode>& out) {
  const int index = static_cast<int>(out.size());
  out.push_back({node, parent});
  for (unsigned i = 0; i < node->mNumChildren; ++i) flatten(node->mChildren[i], index, out);
}

bool same_vector(const aiVector3D& a, const aiVector3D& b) {
  const double size = std::max({1.0, double{std::abs(a.x)}, double{std::abs(a.y)}, double{std::abs(a.z)}});
  return std::abs(a.x - b.x) <= 1e-6 * size && std::abs(a.y - b.y) <= 1e-6 * size && std::abs(a.z - b.z) <= 1e-6 * size;
}

bool same_rotation(const aiQuaternion& a, const aiQuaternion& b) {
  const double dot = std::abs(a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z);
  return dot >= 1.0 - 1e-10;
}

// Whether the channel's keys change the node's transform over time.
bool channel_moves(const aiNodeAnim& ch) {
  for (unsigned k = 1; k < ch.mNumPositionKeys; ++k) {
    if (!same_vector(ch.mPositionKeys[k].mValue, ch.mPositionKeys[0].mValue)) return true;
  }
  for (unsigned k = 1; k < ch.mNumRotationKeys; ++k) {
    if (!same_rotation(ch.mRotationKeys[k].mValue, ch.mRotationKeys[0].mValue)) return true;
  }
  for (unsigned k = 1; k < ch.mNumScalingKeys; ++k) {
    if (!same_vector(ch.mScalingKeys[k].mValue, ch.mScalingKeys[0].mValue)) return true;
  }
  return false;
}

template <class Key>
std::pair<unsigned, double> bracket(const Key* keys, unsigned count, double tick) {
  if (count <= 1 || tick <= keys[0].mTime) return {0, 0.0};
  if (tick >= keys[count - 1].mTime) return {count - 1, 0.0};
  const Key* upper = std::upper_bound(keys, keys + count, tick, [](double t, const Key& k) { return t < k.mTime; });
  const unsigned i = static_cast<unsigned>(upper - keys) - 1;
  const double span = keys[i + 1].mTime - keys[i].mTime;
  return {i, span > 0.0 ? (tick - keys[i].mTime) / span : 0.0};
}

aiVector3D sample_vector(const aiVectorKey* keys, unsigned count, double tick) {
  const auto [i, w] = bracket(keys, count, tick);
  if (w == 0.0) return keys[i].mValue;
  const aiVector3D& a = keys[i].mValue;
  const aiVector3D& b = keys[i + 1].mValue;
  return a + static_cast<ai_real>(w) * (b - a);
}

aiQuaternion sample_rotation(const aiQuatKey* keys, unsigned count, double tick) {
  const auto [i, w] = bracket(keys, count, tick);
  if (w == 0.0) return keys[i].mValue;
  aiQuaternion out;
  aiQuaternion::Interpolate(out, keys[i].mValue, keys[i + 1].mValue, static_cast<ai_real>(w));
  return out.Normalize();
}

// The node's local transform at `tick`: the channel's keys, the node's own
// transform for what the channel does not key.
aiMatrix4x4 sample_local(const aiNodeAnim& ch, const aiMatrix4x4& own, double tick) {
  aiVector3D scaling, position;
  aiQuaternion rotation;
  own.Decompose(scaling, rotation, position);
  if (ch.mNumPositionKeys > 0) position = sample_vector(ch.mPositionKeys, ch.mNumPositionKeys, tick);
  if (ch.mNumRotationKeys > 0) rotation = sample_rotation(ch.mRotationKeys, ch.mNumRotationKeys, tick);
  if (ch.mNumScalingKeys > 0) scaling = sample_vector(ch.mScalingKeys, ch.mNumScalingKeys, tick);
  return aiMatrix4x4(scaling, rotation, position);
}

// FBX files state their axes and unit in metadata that assimp passes on unapplied.
void read_fbx_axes(const aiScene& scene, Armature& armature) {
  if (scene.mMetaData == nullptr) return;
  auto integer = [&](const char* key, int fallback) {
    int32_t value = fallback;
    return scene.mMetaData->Get(key, value) ? static_cast<int>(value) : fallback;
  };
  std::string_view format;
  aiString format_name;
  if (scene.mMetaData->Get("SourceAsset_Format", format_name)) format = format_name.C_Str();
  if (format.find("FBX") == std::string_view::npos) return;
  double unit = 0.0;
  float unit_float = 0.0f;
  if (!scene.mMetaData->Get("UnitScaleFactor", unit)) {
    if (scene.mMetaData->Get("UnitScaleFactor", unit_float)) unit = unit_float;
  }
  if (unit > 0.0) armature.scale = unit / 100.0;  // FBX units are centimetres times this factor
  const int up = integer("UpAxis", 1), up_sign = integer("UpAxisSign", 1);
  const int front = integer("FrontAxis", 2), front_sign = integer("FrontAxisSign", 1);
  const int coord = integer("CoordAxis", 0), coord_sign = integer("CoordAxisSign", 1);
  if (up < 0 || up > 2 || front < 0 || front > 2 || coord < 0 || coord > 2 || up == front || up == coord ||
      front == coord) {
    armature.warnings.push_back(fmt::format("the file's axis metadata (up {}, front {}, coord {}) is inconsistent; "
                                            "its axes are read as they are",
                                            up, front, coord));
    return;
  }
  Mat3 basis = Mat3::Zero();
  basis(0, coord) = coord_sign < 0 ? -1.0 : 1.0;
  basis(1, up) = up_sign < 0 ? -1.0 : 1.0;
  basis(2, front) = front_sign < 0 ? -1.0 : 1.0;
  if (basis.determinant() < 0.0) {
    basis.row(2) *= -1.0;
    armature.warnings.push_back("the file declares left-handed axes; its front axis is mirrored to read it");
  }
  armature.basis = basis;
}

}  // namespace

Mat4 to_eigen(const aiMatrix4x4& m) {
  Mat4 out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return out;
}

aiMatrix4x4 to_assimp(const Mat4& m) {
  return aiMatrix4x4(static_cast<ai_real>(m(0, 0)), static_cast<ai_real>(m(0, 1)), static_cast<ai_real>(m(0, 2)),
                     static_cast<ai_real>(m(0, 3)), static_cast<ai_real>(m(1, 0)), static_cast<ai_real>(m(1, 1)),
                     static_cast<ai_real>(m(1, 2)), static_cast<ai_real>(m(1, 3)), static_cast<ai_real>(m(2, 0)),
                     static_cast<ai_real>(m(2, 1)), static_cast<ai_real>(m(2, 2)), static_cast<ai_real>(m(2, 3)),
                     static_cast<ai_real>(m(3, 0)), static_cast<ai_real>(m(3, 1)), static_cast<ai_real>(m(3, 2)),
                     static_cast<ai_real>(m(3, 3)));
}

Quat rotation_part(const Mat4& m) {
  const Mat3 a = m.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Mat3> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0.0) {  // a mirroring scale: keep the rotation of the mirrored frame
    Mat3 u = svd.matrixU();
    u.col(2) *= -1.0;
    r = u * svd.matrixV().transpose();
  }
  return Quat(r).normalized();
}

std::pair<double, double> key_range(const aiAnimation& animation) {
  double first = INFINITY, last = -INFINITY;
  auto extend = [&](const auto* keys, unsigned count) {
    if (count == 0) return;
    first = std::min(first, keys[0].mTime);
    last = std::max(last, keys[count - 1].mTime);
  };
  for (unsigned c = 0; c < animation.mNumChannels; ++c) {
    const aiNodeAnim& ch = *animation.mChannels[c];
    extend(ch.mPositionKeys, ch.mNumPositionKeys);
    extend(ch.mRotationKeys, ch.mNumRotationKeys);
    extend(ch.mScalingKeys, ch.mNumScalingKeys);
  }
  if (!(first <= last)) return {0.0, 0.0};
  return {first, last};
}

double ticks_per_second(const aiAnimation& animation) {
  return animation.mTicksPerSecond > 0.0 ? animation.mTicksPerSecond : 25.0;  // assimp's stated default
}

Armature find_armature(const aiScene& scene, const std::string& path) {
  Armature a;
  flatten(scene.mRootNode, -1, a.nodes);
  std::map<std::string, int> by_name;
  for (int i = static_cast<int>(a.nodes.size()) - 1; i >= 0; --i) by_name[a.nodes[i].node->mName.C_Str()] = i;
  auto node_named = [&](const aiString& name) {
    const auto it = by_name.find(name.C_Str());
    return it == by_name.end() ? -1 : it->second;
  };
  std::vector<int> mesh_node(scene.mNumMeshes, -1);  // the (first) node that holds each mesh
  for (int i = 0; i < static_cast<int>(a.nodes.size()); ++i) {
    const aiNode* n = a.nodes[i].node;
    for (unsigned m = 0; m < n->mNumMeshes; ++m) {
      if (n->mMeshes[m] < scene.mNumMeshes && mesh_node[n->mMeshes[m]] < 0) mesh_node[n->mMeshes[m]] = i;
    }
  }
  // Bind pose of every skinned bone, in world coordinates.
  a.own_world = node_world_transforms(a, node_channels(a, nullptr), 0.0);
  const std::vector<Mat4>& own_world = a.own_world;
  std::map<int, Mat4> bind;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    for (unsigned b = 0; b < mesh.mNumBones; ++b) {
      const int n = node_named(mesh.mBones[b]->mName);
      if (n < 0) continue;
      a.nodes[n].bone = true;
      const Mat4 holder = mesh_node[m] >= 0 ? own_world[mesh_node[m]] : Mat4(Mat4::Identity());
      bind.emplace(n, holder * to_eigen(mesh.mBones[b]->mOffsetMatrix).inverse());
    }
  }
  bool any_animated = false;
  for (unsigned an = 0; an < scene.mNumAnimations; ++an) {
    const aiAnimation& animation = *scene.mAnimations[an];
    for (unsigned c = 0; c < animation.mNumChannels; ++c) {
      const int n = node_named(animation.mChannels[c]->mNodeName);
      if (n < 0) continue;
      a.nodes[n].animated = any_animated = true;
      if (channel_moves(*animation.mChannels[c])) a.nodes[n].moving = true;
    }
  }
  // The nodes that make an armature: bones and moving nodes (else any animated node).
  std::vector<int> structural;
  for (int i = 0; i < static_cast<int>(a.nodes.size()); ++i) {
    if (a.nodes[i].bone || a.nodes[i].moving) structural.push_back(i);
  }
  if (structural.empty()) {
    for (int i = 0; i < static_cast<int>(a.nodes.size()); ++i) {
      if (a.nodes[i].animated) structural.push_back(i);
    }
  }
  if (structural.empty()) {
    throw InputError(path, 0, any_animated ? "no armature: its animations name no node of the scene"
                                           : "no armature: the file has no bones and no animated nodes");
  }
  const bool any_bone = std::any_of(a.nodes.begin(), a.nodes.end(), [](const SceneNode& n) { return n.bone; });
  if (!any_bone && std::all_of(structural.begin(), structural.end(),
                               [&](int i) { return a.nodes[i].node->mNumMeshes > 0; })) {
    throw InputError(path, 0, "no armature: its animations move mesh objects, not bones");
  }
  // Several armatures (subtrees under the scene root): the one with the most such nodes.
  auto top_of = [&](int i) {
    while (a.nodes[i].parent > 0) i = a.nodes[i].parent;
    return i;
  };
  std::map<int, std::vector<int>> groups;
  for (int i : structural) groups[top_of(i)].push_back(i);
  auto chosen = groups.begin();
  for (auto it = groups.begin(); it != groups.end(); ++it) {
    if (it->second.size() > chosen->second.size()) chosen = it;
  }
  if (groups.size() > 1) {
    std::string others;
    for (auto it = groups.begin(); it != groups.end(); ++it) {
      if (it != chosen) others += fmt::format("{}'{}' ({} nodes)", others.empty() ? "" : ", ", a.nodes[it->first].node->mName.C_Str(), it->second.size());
    }
    a.warnings.push_back(fmt::format("the scene has {} armatures; read '{}' ({} nodes), ignored {}", groups.size(),
                                     a.nodes[chosen->first].node->mName.C_Str(), chosen->second.size(), others));
  }
  // Root joint: the lowest common ancestor of the chosen nodes.
  auto ancestors = [&](int i) {
    std::vector<int> path_up;
    for (; i >= 0; i = a.nodes[i].parent) path_up.push_back(i);
    std::reverse(path_up.begin(), path_up.end());
    return path_up;
  };
  std::vector<int> common = ancestors(chosen->second.front());
  for (int i : chosen->second) {
    const std::vector<int> other = ancestors(i);
    size_t k = 0;
    while (k < common.size() && k < other.size() && common[k] == other[k]) ++k;
    common.resize(k);
  }
  const int root = common.back();
  // Joints: nodes under the root that are bones, animated, or lead to one.
  std::vector<char> is_joint(a.nodes.size(), 0);
  auto under_root = [&](int i) {
    for (; i >= 0; i = a.nodes[i].parent) {
      if (i == root) return true;
    }
    return false;
  };
  for (int i = static_cast<int>(a.nodes.size()) - 1; i >= root; --i) {
    if (!under_root(i)) continue;
    if (a.nodes[i].bone || a.nodes[i].animated || i == root) is_joint[i] = 1;
    if (is_joint[i] && i != root) is_joint[a.nodes[i].parent] = 1;
  }
  std::vector<int> joint_of(a.nodes.size(), -1);
  for (int i = root; i < static_cast<int>(a.nodes.size()); ++i) {
    if (!is_joint[i]) continue;
    joint_of[i] = a.joint_count();
    a.joints.push_back(i);
    a.joint_parents.push_back(i == root ? -1 : joint_of[a.nodes[i].parent]);
  }
  // Rest: the bind pose of skinned bones, the nodes' own relative transforms elsewhere.
  for (int j = 0; j < a.joint_count(); ++j) {
    const int n = a.joints[j];
    const auto it = bind.find(n);
    if (it != bind.end()) {
      a.rest.push_back(it->second);
    } else if (a.joint_parents[j] < 0) {
      a.rest.push_back(own_world[n]);
    } else {
      const int pn = a.nodes[n].parent;
      a.rest.push_back(a.rest[a.joint_parents[j]] * own_world[pn].inverse() * own_world[n]);
    }
  }
  for (const Mat4& m : a.rest) a.rest_rotations.push_back(rotation_part(m));
  // End sites: childless, meshless nodes hanging from a joint (Blender's bone tips).
  for (int i = root + 1; i < static_cast<int>(a.nodes.size()); ++i) {
    const aiNode* n = a.nodes[i].node;
    const int parent_joint = a.nodes[i].parent >= 0 ? joint_of[a.nodes[i].parent] : -1;
    if (is_joint[i] || parent_joint < 0 || n->mNumChildren > 0 || n->mNumMeshes > 0) continue;
    a.end_site_joints.push_back(parent_joint);
    a.end_site_nodes.push_back(i);
    a.end_site_rest.push_back(a.rest[parent_joint] * own_world[a.nodes[i].parent].inverse() * own_world[i]);
  }
  read_fbx_axes(scene, a);
  return a;
}

std::vector<std::string> joint_names(const Armature& armature) {
  std::vector<std::string> names;
  std::set<std::string> used;
  for (int j = 0; j < armature.joint_count(); ++j) {
    std::string name = armature.joint_name(j);
    if (name.empty()) name = "joint_" + std::to_string(j);
    const std::string base = name;
    for (int k = 2; used.count(name) > 0; ++k) name = base + "_" + std::to_string(k);
    used.insert(name);
    names.push_back(std::move(name));
  }
  return names;
}

std::vector<const aiNodeAnim*> node_channels(const Armature& armature, const aiAnimation* animation) {
  std::vector<const aiNodeAnim*> out(armature.nodes.size(), nullptr);
  if (animation == nullptr) return out;
  std::map<std::string, const aiNodeAnim*> by_name;
  for (unsigned c = 0; c < animation->mNumChannels; ++c) {
    by_name.emplace(animation->mChannels[c]->mNodeName.C_Str(), animation->mChannels[c]);
  }
  for (size_t i = 0; i < armature.nodes.size(); ++i) {
    const auto it = by_name.find(armature.nodes[i].node->mName.C_Str());
    if (it != by_name.end()) out[i] = it->second;
  }
  return out;
}

std::vector<Mat4> node_world_transforms(const Armature& armature, const std::vector<const aiNodeAnim*>& channels,
                                        double tick) {
  std::vector<Mat4> world(armature.nodes.size());
  for (size_t i = 0; i < armature.nodes.size(); ++i) {
    const SceneNode& n = armature.nodes[i];
    const Mat4 local = to_eigen(channels[i] != nullptr ? sample_local(*channels[i], n.node->mTransformation, tick)
                                                       : n.node->mTransformation);
    world[i] = n.parent < 0 ? local : Mat4(world[n.parent] * local);
  }
  return world;
}

}  // namespace nec::assets
