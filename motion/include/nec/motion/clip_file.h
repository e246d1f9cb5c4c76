// Reading and writing motion files of every format nec knows: BVH here,
// rigged assets (FBX, glTF, Collada, .x in; GLB out) when the assets library
// has registered them. motion/ itself depends on no asset library; `nec` and
// the tests call nec::assets::register_asset_formats() once at startup.
//
//   std::vector<Clip> clips = read_clips("wuson.x");   // one clip per animation, named after it
//   Clip walk = read_clip("wuson.x#Wuson_Walk");       // one animation of a file
//   Clip first = read_clip("walk.bvh");
//   write_clip("dragon_walk.glb", out, "dragon.fbx", "walk");  // onto a copy of the asset
#pragma once

#include "nec/motion/motion.h"

#include <functional>
#include <string>
#include <vector>

namespace nec {

struct ClipReadOptions {
  double fps = 0.0;  // > 0: the motion's true frame rate, replacing what the file says (BVH Frame Time, asset keys are sampled at it)
};

// A reader of one family of formats: all the clips (animations) a file holds.
struct ClipFormat {
  std::string description;              // e.g. "rigged assets through assimp"
  std::vector<std::string> extensions;  // lower case, with the dot: ".fbx"
  std::function<std::vector<Clip>(const std::string& path, const ClipReadOptions& options)> read;
};

// Adds a format (a later registration of an extension wins).
void register_clip_format(ClipFormat format);

// A writer of an asset format: the bytes of a copy of the asset `target`
// with `clip` (on the skeleton read from `target`) as a new animation named `name`.
struct ClipWriter {
  std::string description;
  std::vector<std::string> extensions;  // lower case, with the dot: ".glb"
  std::function<std::string(const Clip& clip, const std::string& target, const std::string& name)> encode;
};
void register_clip_writer(ClipWriter writer);
// Extensions read by read_clips(): ".bvh" and the registered ones.
std::vector<std::string> motion_file_extensions();
bool is_motion_file(const std::string& path);
bool is_bvh_file(const std::string& path);  // by its extension, in any case

// Every clip in the file; a BVH file whose Frame Time does not fit its motion
// gets a warning (motion/frame_rate.h). `path` may name one animation as FILE#NAME (used when
// FILE#NAME itself is no file). Throws InputError naming the file for an unknown
// extension, an unreadable file or a missing animation.
std::vector<Clip> read_clips(const std::string& path, const ClipReadOptions& options = {});
// The one clip a file holds; of several animations the first, with a warning
// naming the others (choose one with FILE#NAME).
Clip read_clip(const std::string& path, const ClipReadOptions& options = {});

// Throws InputError, before any work is done, when `out` cannot be written:
// an extension nec does not write, or an asset output whose `target` (the
// skeleton's file) is no asset.
void check_clip_output(const std::string& out, const std::string& target);
// BVH for .bvh (atomic); a registered asset format onto `target`, the
// animation named `name`.
void write_clip(const std::string& out, const Clip& clip, const std::string& target, const std::string& name);
// The bytes write_clip() would write to a file with extension `ext` (".glb"):
// "" when no writer of `ext` is registered or `target` is no asset.
std::string encode_clip_onto_asset(const std::string& ext, const Clip& clip, const std::string& target,
                                   const std::string& name);

}  // namespace nec
