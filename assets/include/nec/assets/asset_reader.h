// Rigged assets in: the armature and its animations of an FBX, glTF/GLB,
// Collada or DirectX .x file, read through assimp into nec's Skeleton and Motion.
//
//   assets::register_asset_formats();           // once: read_clips() takes these files too
//   std::vector<Clip> clips = read_clips("wuson.x");   // one clip per animation
//
// What is read (docs/assets.md has the reasons):
// - The armature: the nodes that deform a mesh (bones) or that an animation
//   moves. Its root joint is their lowest common ancestor; nodes above it
//   (an "Armature" object, unit or axis conversions) are baked into the
//   world transforms. Of several armatures the one with the most bones is
//   read (a warning names the others). Leaf nodes under joints (Blender's
//   "_end" tips) become end sites; meshes and cameras are ignored.
// - The rest pose: the bind pose of the skinned bones, the nodes' own
//   transforms elsewhere; joint frames aligned with the world at rest (as BVH).
// - Units and up axis: metres, +Y up (FBX UnitScaleFactor and axis metadata;
//   glTF is metres and +Y up; assimp applies Collada's <unit> and <up_axis>).
// - Keys are sampled at `fps` (linear / slerp between keys, held before the
//   first and after the last); nodes without keys hold their rest transform.
//   Non-root joints whose animated translation leaves their rest offset get
//   position channels (preprocessing folds small ones, rejects stretching).
// - A file with no animation gives one rest frame (a target skeleton).
// World joint positions are kept exactly (to float precision).
#pragma once

#include "nec/motion/clip_file.h"

#include <string>
#include <vector>

namespace nec::assets {

// Extensions read through assimp, lower case with the dot.
const std::vector<std::string>& asset_extensions();

// Every animation of the file as a clip named after it. `options.fps` is the
// sampling rate (0: 30 fps). Throws InputError naming the file: unreadable,
// no armature, or an armature nec cannot express.
std::vector<Clip> read_asset(const std::string& path, const ClipReadOptions& options = {});

// Registers read_asset() with motion/'s read_clips() for asset_extensions(),
// and animation_onto_asset() with write_clip() (asset_writer.h).
void register_asset_formats();  // once per process; later calls do nothing

}  // namespace nec::assets
