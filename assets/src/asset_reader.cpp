// Rigged assets -> clips: the armature's world transforms, re-expressed with
// world-aligned rest frames (BVH semantics) in metres, +Y up.
#include "nec/assets/asset_reader.h"

#include "armature.h"

#include "nec/assets/asset_writer.h"

#include "nec/motion/error.h"

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <mutex>

namespace nec::assets {
namespace {

constexpr double kDefaultFps = 30.0;

struct WorldPose {
  std::vector<Vec3> positions;  // (J) metres, +Y up
  std::vector<Quat> turns;      // (J) world rotation from the rest frame
};

WorldPose world_pose(const Armature& a, const std::vector<Mat4>& node_world) {
  WorldPose pose;
  for (int j = 0; j < a.joint_count(); ++j) {
    const Mat4& w = node_world[a.joints[j]];
    pose.positions.push_back(a.position(w));
    const Mat3 turn =
        a.basis * (rotation_part(w) * a.rest_rotations[j].conjugate()).toRotationMatrix() * a.basis.transpose();
    pose.turns.push_back(Quat(turn).normalized());
  }
  return pose;
}

Skeleton rest_skeleton(const Armature& a) {
  Skeleton s;
  const std::vector<std::string> names = joint_names(a);
  for (int j = 0; j < a.joint_count(); ++j) {
    const int p = a.joint_parents[j];
    const Vec3 offset = p < 0 ? a.position(a.rest[j]) : Vec3(a.position(a.rest[j]) - a.position(a.rest[p]));
    s.add_joint(names[j], p, offset,
                p < 0 ? ChannelLayout::position_rotations(EulerOrder::ZXY) : ChannelLayout::rotations(EulerOrder::ZXY));
  }
  for (size_t e = 0; e < a.end_site_joints.size(); ++e) {
    const int p = a.end_site_joints[e];
    s.end_sites.push_back({p, a.position(a.end_site_rest[e]) - a.position(a.rest[p])});
  }
  s.validate();
  return s;
}

Clip sample_clip(const Armature& a, const Skeleton& skeleton, const aiAnimation* animation, double fps) {
  const std::vector<const aiNodeAnim*> channels = node_channels(a, animation);
  double first = 0.0, last = 0.0, tps = 1.0;
  if (animation != nullptr) {
    std::tie(first, last) = key_range(*animation);
    tps = ticks_per_second(*animation);
  }
  // Key times pass through float (glTF stores seconds as float): a hundredth of a frame short is on the frame.
  const int frames = static_cast<int>(std::floor((last - first) / tps * fps + 1e-2)) + 1;
  Clip clip;
  clip.skeleton = skeleton;
  clip.motion = Motion::rest(skeleton, frames, fps);
  const int joints = skeleton.joint_count();
  // assimp computes in float: chains of float matrices move a joint by ~1e-6 diameters.
  const double tolerance = 1e-4 * std::max(skeleton.diameter(), 1e-9);
  std::vector<double> drift(static_cast<size_t>(joints), 0.0);  // largest departure from the rest offset
  for (int f = 0; f < frames; ++f) {
    const WorldPose pose = world_pose(a, node_world_transforms(a, channels, first + f / fps * tps));
    for (int j = 0; j < joints; ++j) {
      const int p = skeleton.parents[j];
      if (p < 0) {
        clip.motion.rotation(f, j) = pose.turns[j];
        clip.motion.translation(f, j) = pose.positions[j];
        continue;
      }
      clip.motion.rotation(f, j) = (pose.turns[p].conjugate() * pose.turns[j]).normalized();
      const Vec3 local = pose.turns[p].conjugate() * (pose.positions[j] - pose.positions[p]);
      clip.motion.translation(f, j) = local;
      drift[j] = std::max(drift[j], (local - skeleton.offsets[j]).norm());
    }
  }
  // Joints that keep their offset read as rotations only; the others get position channels.
  for (int j = 1; j < joints; ++j) {
    if (drift[j] > tolerance) {
      clip.skeleton.channels[j] = ChannelLayout::position_rotations(EulerOrder::ZXY);
      continue;
    }
    for (int f = 0; f < frames; ++f) clip.motion.translation(f, j) = skeleton.offsets[j];
  }
  clip.warnings = a.warnings;
  return clip;
}

}  // namespace

const std::vector<std::string>& asset_extensions() {
  static const std::vector<std::string> extensions{".fbx", ".gltf", ".glb", ".dae", ".zae", ".x"};
  return extensions;
}

std::vector<Clip> read_asset(const std::string& path, const ClipReadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, 0, "no such file");
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);  // no $AssimpFbx$ helper nodes
  const aiScene* scene = importer.ReadFile(path, 0);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw InputError(path, 0, std::string("cannot read the asset: ") + importer.GetErrorString());
  }
  const Armature armature = find_armature(*scene, path);
  const Skeleton skeleton = rest_skeleton(armature);
  const double fps = options.fps > 0.0 ? options.fps : kDefaultFps;
  std::vector<Clip> clips;
  if (scene->mNumAnimations == 0) {
    clips.push_back(sample_clip(armature, skeleton, nullptr, fps));
    clips.back().warnings.push_back("the file has no animation: one frame of its rest pose");
  }
  for (unsigned i = 0; i < scene->mNumAnimations; ++i) {
    clips.push_back(sample_clip(armature, skeleton, scene->mAnimations[i], fps));
    const std::string name = scene->mAnimations[i]->mName.C_Str();
    clips.back().name = name.empty() ? fmt::format("animation_{}", i + 1) : name;
  }
  return clips;
}

void register_asset_formats() {
  static std::once_flag registered;  // nec's main and the studio both call it
  std::call_once(registered, [] {
    register_clip_format({"rigged assets (FBX, glTF, Collada, DirectX) through assimp", asset_extensions(), read_asset});
    register_clip_writer({"the motion as a new animation on a copy of the asset (GLB)", asset_output_extensions(),
                          animation_onto_asset});
  });
}

}  // namespace nec::assets
