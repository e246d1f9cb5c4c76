// Clip -> a new animation on a copy of the asset, exported as GLB.
#include "nec/assets/asset_writer.h"

#include "armature.h"

#include "nec/motion/error.h"
#include "nec/motion/kinematics.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace nec::assets {
namespace {

// Rotations are turns from the rest pose: the motion's rest must be the asset's
// (as on the skeleton nec reads from it), else the pose comes out bent. A few
// bones may differ: preprocessing folds a joint whose animation holds it off its
// bind offset into a new offset (Testwuson, BCN_Epileptic). Another rest pose
// (a T-pose motion on an A-pose asset) turns whole limbs: a quarter of the bones.
void check_same_rest(const Armature& a, const Clip& clip, const std::vector<int>& clip_joint, const std::string& asset) {
  constexpr double kMaxDegrees = 5.0;
  int compared = 0, off = 0;
  double worst = 0.0;
  std::string worst_bone;
  for (int j = 0; j < a.joint_count(); ++j) {
    const int parent = a.joint_parents[j];
    const int c = clip_joint[static_cast<size_t>(j)];
    if (parent < 0 || c < 0 || clip.skeleton.parents[c] < 0 || clip.skeleton.parents[c] != clip_joint[parent]) continue;
    const Vec3 bone = a.position(a.rest[j]) - a.position(a.rest[parent]);
    const Vec3& offset = clip.skeleton.offsets[c];
    if (bone.norm() < 1e-9 || offset.norm() < 1e-9) continue;
    const double degrees = std::acos(std::clamp(bone.normalized().dot(offset.normalized()), -1.0, 1.0)) * kDegreesPerRadian;
    ++compared;
    if (degrees <= kMaxDegrees) continue;
    ++off;
    if (degrees > worst) worst = degrees, worst_bone = clip.skeleton.names[c];
  }
  if (off > std::max(1, compared / 4)) {
    throw InputError(asset, 0, fmt::format(
        "the motion's rest pose is not this asset's: {} of {} bones point more than {:.0f}° away from the asset's "
        "('{}' {:.0f}°); write motion made on this asset's skeleton (`nec transfer --to`, `decode --skeleton`, "
        "`generate --skeleton` with this file, or `nec convert` of the asset itself)",
        off, compared, kMaxDegrees, worst_bone, worst));
  }
}

// The node transforms (file coordinates) of the armature's joints in every frame.
std::vector<std::vector<Mat4>> joint_world_transforms(const Armature& a, const Clip& clip, const std::string& asset) {
  const std::vector<std::string> names = joint_names(a);
  std::vector<int> clip_joint(names.size(), -1);
  int matched = 0;
  for (size_t j = 0; j < names.size(); ++j) {
    clip_joint[j] = clip.skeleton.find(names[j]);
    matched += clip_joint[j] >= 0;
  }
  // The motion must be on this skeleton: each of its joints one of the armature's, and most of those there.
  std::string foreign;
  int foreign_count = 0;
  for (const std::string& name : clip.skeleton.names) {
    if (std::find(names.begin(), names.end(), name) != names.end()) continue;
    if (++foreign_count <= 3) foreign += (foreign.empty() ? "'" : ", '") + name + "'";
  }
  if (foreign_count > 0 || 2 * matched < static_cast<int>(names.size())) {
    throw InputError(asset, 0, fmt::format(
        "the motion is not on this asset's skeleton: {} of its {} joints are not in the armature{}{}, {} of the "
        "armature's {} joints are in the motion",
        foreign_count, clip.skeleton.joint_count(), foreign.empty() ? "" : " (", foreign.empty() ? "" : foreign + (foreign_count > 3 ? ", ...)" : ")"),
        matched, names.size()));
  }
  check_same_rest(a, clip, clip_joint, asset);
  const Pose pose = forward_kinematics(clip.skeleton, clip.motion);
  const Mat3 back = a.basis.transpose();  // nec's axes -> the file's
  std::vector<std::vector<Mat4>> world(static_cast<size_t>(clip.motion.frame_count),
                                       std::vector<Mat4>(names.size(), Mat4::Identity()));
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    std::vector<Mat4>& w = world[static_cast<size_t>(t)];
    for (int j = 0; j < a.joint_count(); ++j) {
      const int parent = a.joint_parents[j];
      const int c = clip_joint[static_cast<size_t>(j)];
      if (c < 0) {  // held at rest relative to its parent (node transforms relative to the one above)
        const Mat4 above = parent < 0 ? a.above_root() : w[parent];
        w[j] = above * to_eigen(a.nodes[a.joints[j]].node->mTransformation);
        continue;
      }
      // World turn from rest in nec's axes -> in the file's, applied to the rest transform (keeps its scale).
      const Mat3 turn = back * pose.rotation(t, c).toRotationMatrix() * a.basis;
      Mat4 m = Mat4::Identity();
      m.topLeftCorner<3, 3>() = turn * a.rest[j].topLeftCorner<3, 3>();
      m.topRightCorner<3, 1>() = back * pose.position(t, c) / a.scale;
      w[j] = m;
    }
  }
  return world;
}

aiAnimation* make_animation(const Armature& a, const std::vector<std::vector<Mat4>>& world, double fps,
                            const std::string& name) {
  auto animation = std::make_unique<aiAnimation>();
  animation->mName = aiString(name);
  animation->mTicksPerSecond = fps;
  const unsigned frames = static_cast<unsigned>(world.size());
  animation->mDuration = frames > 0 ? frames - 1 : 0;
  animation->mNumChannels = static_cast<unsigned>(a.joint_count());
  animation->mChannels = new aiNodeAnim*[animation->mNumChannels];
  for (int j = 0; j < a.joint_count(); ++j) {
    auto* channel = new aiNodeAnim;
    animation->mChannels[j] = channel;
    const aiNode* node = a.nodes[a.joints[j]].node;
    channel->mNodeName = node->mName;
    channel->mNumPositionKeys = channel->mNumRotationKeys = channel->mNumScalingKeys = frames;
    channel->mPositionKeys = new aiVectorKey[frames];
    channel->mRotationKeys = new aiQuatKey[frames];
    channel->mScalingKeys = new aiVectorKey[frames];
    const int parent = a.joint_parents[j];
    for (unsigned t = 0; t < frames; ++t) {
      const Mat4 above = parent < 0 ? a.above_root() : world[t][parent];
      const aiMatrix4x4 local = to_assimp(above.inverse() * world[t][j]);
      aiVector3D scaling, position;
      aiQuaternion rotation;
      local.Decompose(scaling, rotation, position);
      channel->mPositionKeys[t] = aiVectorKey(t, position);
      channel->mRotationKeys[t] = aiQuatKey(t, rotation);
      channel->mScalingKeys[t] = aiVectorKey(t, scaling);
    }
  }
  return animation.release();
}

// `name`, or with a number appended if the asset has an animation of that name (glTF's exporter needs them distinct).
std::string unused_animation_name(const aiScene& scene, const std::string& name) {
  auto used = [&](const std::string& candidate) {
    for (unsigned i = 0; i < scene.mNumAnimations; ++i) {
      if (candidate == scene.mAnimations[i]->mName.C_Str()) return true;
    }
    return false;
  };
  std::string out = name;
  for (int k = 2; used(out); ++k) out = name + "_" + std::to_string(k);
  return out;
}

// Puts `animation` first among the scene's animations (the scene owns it after).
void add_first(aiScene& scene, aiAnimation* animation) {
  auto** all = new aiAnimation*[scene.mNumAnimations + 1];
  all[0] = animation;
  for (unsigned i = 0; i < scene.mNumAnimations; ++i) all[i + 1] = scene.mAnimations[i];
  delete[] scene.mAnimations;
  scene.mAnimations = all;
  ++scene.mNumAnimations;
}

// glTF is metres and +Y up: a file in other units or axes (FBX metadata) gets a
// new scene root that converts, so the copy stands as nec reads the original.
void convert_to_metres_y_up(aiScene& scene, const Armature& a) {
  if (a.scale == 1.0 && a.basis.isIdentity()) return;
  Mat4 convert = Mat4::Identity();
  convert.topLeftCorner<3, 3>() = a.scale * a.basis;
  auto* root = new aiNode("nec_metres_y_up");
  root->mTransformation = to_assimp(convert);
  root->mNumChildren = 1;
  root->mChildren = new aiNode*[1]{scene.mRootNode};
  scene.mRootNode->mParent = root;
  scene.mRootNode = root;
}

}  // namespace

const std::vector<std::string>& asset_output_extensions() {
  static const std::vector<std::string> extensions{".glb"};
  return extensions;
}

std::string animation_onto_asset(const Clip& clip, const std::string& asset, const std::string& name) {
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);  // as the reader: the same nodes
  if (importer.ReadFile(asset, 0) == nullptr) {
    throw InputError(asset, 0, std::string("cannot read the asset: ") + importer.GetErrorString());
  }
  const std::unique_ptr<aiScene> scene(importer.GetOrphanedScene());
  const Armature armature = find_armature(*scene, asset);
  add_first(*scene, make_animation(armature, joint_world_transforms(armature, clip, asset), clip.motion.fps,
                                   unused_animation_name(*scene, name.empty() ? std::string("nec") : name)));
  convert_to_metres_y_up(*scene, armature);
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), "glb2", 0);
  if (blob == nullptr) throw std::runtime_error(asset + ": the glTF exporter failed: " + exporter.GetErrorString());
  return std::string(static_cast<const char*>(blob->data), blob->size);
}

}  // namespace nec::assets
