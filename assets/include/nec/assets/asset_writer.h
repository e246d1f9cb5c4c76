// Motion out onto the user's own asset: a copy of the rigged asset (mesh,
// skin weights, materials, its own animations) with the motion added as a
// new animation, written as GLB through assimp's glTF 2 exporter.
//
//   Clip out = ...;                                  // on the skeleton read_clip("dragon.fbx") gives
//   write_file_atomic("dragon_walk.glb", assets::animation_onto_asset(out, "dragon.fbx", "walk"));
//
// The clip's joints are matched to the armature's by name; armature joints the
// clip lacks (a dummy root that preprocessing merged) keep their rest transform
// relative to their parent. The new animation comes first (named `name`, with
// "_2" ... appended if the asset has one of that name), so that viewers that
// play one animation play it; keys at every frame of the clip.
#pragma once

#include "nec/motion/motion.h"

#include <string>
#include <vector>

namespace nec::assets {

// Extensions written: ".glb" (one self-contained file).
const std::vector<std::string>& asset_output_extensions();

// Throws InputError naming the file for an unreadable asset, a clip with no
// joint of its armature, or a clip whose rest pose is not the asset's (more than
// a quarter of the bones 5° off: its rotations would bend the asset); std::runtime_error
// when the export fails.
// Returns the GLB file's bytes.
std::string animation_onto_asset(const Clip& clip, const std::string& asset, const std::string& name);

}  // namespace nec::assets
