// nec info | convert | normalize | augment: single-file commands (BVH, or a rigged asset read as BVH).
#include "command_line.h"
#include "commands.h"

#include "nec/corpus/augment.h"
#include "nec/motion/bvh.h"
#include "nec/motion/clip_file.h"
#include "nec/motion/frame_rate.h"
#include "nec/motion/names.h"
#include "nec/corpus/preprocess.h"
#include "nec/corpus/stance.h"
#include "nec/corpus/rest_pose.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>

namespace nec::app {
namespace {

std::string layout_text(const ChannelLayout& layout) {
  std::string out;
  for (int c = 0; c < layout.count; ++c) {
    if (!out.empty()) out += ' ';
    out += channel_name(layout.channels[c]);
  }
  return out.empty() ? "(none)" : out;
}

void print_tree(const Skeleton& s) {
  const auto children = s.children_lists();
  for (int j : s.depth_first_order()) {
    fmt::print("  {:>3}  {}{}  [{}]  bone {:.4g}  ({})\n", j, std::string(2 * s.depth(j), ' '), s.names[j],
               s.channels[j].count, s.offsets[j].norm(), canonical_joint_name(s.names[j]));
  }
}

void declare_source_fps(CommandLine& cli) {
  cli.option("--source-fps", "FPS", "0",
             "the motion's true frame rate, replacing the file's (BVH Frame Time); assets are sampled at it\n"
             "(0: the file's rate; assets 30 fps)");
}

ClipReadOptions read_options(const CommandLine& cli) {
  ClipReadOptions options;
  options.fps = cli.number("--source-fps");
  if (options.fps < 0) throw UsageError("--source-fps must be >= 0");
  return options;
}

EulerOrder parse_order_option(const std::string& text) {
  const auto order = parse_euler_order(text);
  if (!order) throw UsageError("--order must be one of XYZ XZY YXZ YZX ZXY ZYX, got '" + text + "'");
  return *order;
}

}  // namespace

int run_info(int argc, char** argv) {
  CommandLine cli("nec info",
                  "Print a motion file's skeleton and motion summary: BVH, or a rigged asset (FBX, glTF/GLB,\n"
                  "Collada, .x) with its armature read as BVH would hold it, one line per animation.");
  cli.positional("FILE", "BVH file or rigged asset to describe (FILE#NAME: one animation of an asset)");
  cli.flag("--no-tree", "omit the joint tree");
  cli.flag("--json", "print one JSON line: joints, end_sites, frames, fps, diameter (the first animation)");
  declare_source_fps(cli);
  cli.example("nec info /usr/share/assimp/models/BVH/01_01.bvh");
  cli.example("nec info /usr/share/assimp/models/X/Testwuson.X");
  if (!cli.parse(argc, argv)) return 0;
  const std::string path = cli.positional_value("FILE");
  const std::vector<Clip> clips = read_clips(path, read_options(cli));
  const Clip& clip = clips.front();
  const Skeleton& s = clip.skeleton;
  const Motion& m = clip.motion;
  if (cli.is_set("--json")) {
    fmt::print("{{\"joints\": {}, \"end_sites\": {}, \"frames\": {}, \"fps\": {:.9g}, \"diameter\": {:.9g}, "
               "\"animations\": {}}}\n",
               s.joint_count(), s.end_sites.size(), m.frame_count, m.fps, s.diameter(), clips.size());
    return 0;
  }
  fmt::print("file      {}\n", path);
  fmt::print("joints    {} ({} end sites, {} leaves, max depth {})\n", s.joint_count(), s.end_sites.size(),
             s.leaves().size(), [&] {
               int d = 0;
               for (int j = 0; j < s.joint_count(); ++j) d = std::max(d, s.depth(j));
               return d;
             }());
  if (clips.size() == 1 && clip.name.empty()) {
    fmt::print("frames    {} at {:.6g} fps ({:.2f} s)\n", m.frame_count, m.fps, m.duration_seconds());
  } else {
    for (const Clip& c : clips) {
      fmt::print("animation '{}': {} frames at {:.6g} fps ({:.2f} s)\n", c.name, c.motion.frame_count, c.motion.fps,
                 c.motion.duration_seconds());
    }
  }
  fmt::print("diameter  {:.6g} (longest root-to-leaf chain, {})\n", s.diameter(),
             is_bvh_file(path) ? "file units" : "metres");
  const FrameRateCheck rate = check_frame_rate(clip);
  if (rate.turn_per_frame > 0.0) {
    fmt::print("turning   {:.3g}° per frame, {:.3g}°/s (median over frames of the joints' mean)\n", rate.turn_per_frame,
               rate.turn_per_second);
  }
  if (rate.travel_per_frame > 0.0) {
    fmt::print("travel    {:.3g} body sizes per frame, {:.3g}/s (median over frames of the root's move)\n",
               rate.travel_per_frame, rate.travel_per_second);
  }
  PreprocessOptions as_read;  // every frame, one frame enough: the limbs of a rig without motion too
  as_read.target_fps = 0.0;
  as_read.min_frames = 1;
  const PreparedClip prepared = preprocess(clip, path, as_read);
  const LimbAngles limbs = prepared.report.accepted() ? measure_limbs(prepared.clip, prepared.canonical_names)
                                                      : LimbAngles{};
  if (limbs.found) {
    fmt::print("limbs     upper arms {:.0f}° from hanging (median), thighs swing {:.0f}° (5th to 95th percentile)\n",
               limbs.arms_from_hanging, limbs.thigh_swing);
  }
  std::map<std::string, int> layouts;
  for (const ChannelLayout& layout : s.channels) ++layouts[layout_text(layout)];
  for (const auto& [text, count] : layouts) fmt::print("channels  {} joint(s): {}\n", count, text);
  for (const std::string& warning : clip.warnings) fmt::print("warning   {}\n", warning);
  if (!cli.is_set("--no-tree")) {
    fmt::print("tree      index, name, channel count, bone length, canonical name\n");
    print_tree(s);
  }
  return 0;
}

int run_convert(int argc, char** argv) {
  CommandLine cli("nec convert",
                  "Write a motion file as BVH: a BVH file unchanged or with another Euler order, or the armature\n"
                  "and one animation of a rigged asset (FBX, glTF/GLB, Collada, .x) in metres, +Y up. With --onto,\n"
                  "write a copy of that asset (mesh, skin, materials) with IN's motion added as a GLB.");
  cli.positional("IN", "input BVH file or rigged asset (IN#NAME: one animation of an asset)");
  cli.option("-o", "OUT", "", "output: .bvh, or .glb with --onto", true);
  cli.option("--order", "ORDER", "keep", "Euler order of every rotated joint: XYZ XZY YXZ YZX ZXY ZYX, or keep");
  cli.option("--onto", "ASSET", "", "the rigged asset whose skeleton IN's motion is on (e.g. a BVH that nec wrote\n"
                                    "with --to / --skeleton ASSET): OUT.glb is the asset with that motion added");
  declare_source_fps(cli);
  cli.example("nec convert walk.bvh -o walk_xyz.bvh --order XYZ");
  cli.example("nec convert /usr/share/assimp/models/X/Testwuson.X#Wuson_Walk -o wuson_walk.bvh");
  cli.example("nec convert dragon_walk.bvh --onto dragon.fbx -o dragon_walk.glb");
  if (!cli.parse(argc, argv)) return 0;
  const std::string in = cli.positional_value("IN");
  const std::string out = cli.value("-o");
  const std::string onto = cli.value("--onto");
  if (onto.empty() && !is_bvh_file(out)) throw UsageError("-o " + out + ": only BVH is written without --onto ASSET");
  if (!onto.empty()) check_clip_output(out, onto);
  BvhWriteOptions options;
  if (cli.value("--order") != "keep") options.euler_order = parse_order_option(cli.value("--order"));
  const Clip clip = read_clip(in, read_options(cli));
  for (const std::string& warning : clip.warnings) fmt::print(stderr, "nec: warning: {}: {}\n", in, warning);
  if (onto.empty()) {
    write_bvh(out, clip.skeleton, clip.motion, options);
  } else {
    write_clip(out, clip, onto, clip.name.empty() ? std::filesystem::path(in).stem().string() : clip.name);
  }
  fmt::print("wrote {} ({} joints, {} frames)\n", out, clip.skeleton.joint_count(), clip.motion.frame_count);
  return 0;
}

int run_normalize(int argc, char** argv) {
  CommandLine cli("nec normalize",
                  "Apply the unified preprocessing (dummy root merge, root-only translation, unit diameter, +Y up,\n"
                  "frame 0 facing +Z, corpus frame rate, the canonical rest pose: the clip's mean pose with\n"
                  "world-aligned joint frames) and write the result; prints what was changed.");
  cli.positional("IN", "input BVH file or rigged asset");
  cli.flag("--fold-translations", "fold every non-root joint's translation into its offset, even when it varies more\n"
                                   "than the jitter limits (1 % of the diameter, 10 % of the bone)");
  cli.flag("--keep-rest", "keep the file's rest pose and joint frames (what the models see is the canonical rest)");
  cli.option("-o", "OUT.bvh", "", "output BVH file", true);
  cli.option("--fps", "FPS", "30", "target frame rate; 0 keeps the file's");
  cli.option("--up", "AXIS", "auto", "up axis of the input: auto, y or z");
  cli.example("nec normalize dog.bvh -o dog_normalized.bvh --fps 30");
  if (!cli.parse(argc, argv)) return 0;
  PreprocessOptions options;
  options.target_fps = cli.number("--fps");
  if (options.target_fps < 0) throw UsageError("--fps must be >= 0");
  options.up = cli.up_axis("--up");
  options.canonical_rest = !cli.is_set("--keep-rest");
  options.fold_any_translation = cli.is_set("--fold-translations");
  const std::string path = cli.positional_value("IN");
  const PreparedClip prepared = preprocess(read_clip(path), path, options);
  for (const std::string& change : prepared.report.changes) fmt::print("{}: {}\n", path, change);
  if (!prepared.report.accepted()) {
    fmt::print(stderr, "nec: error: {}: rejected: {}\n", path, prepared.report.rejection);
    return 1;
  }
  write_bvh(cli.value("-o"), prepared.clip.skeleton, prepared.clip.motion);
  fmt::print("wrote {} ({} joints, {} frames at {:.6g} fps)\n", cli.value("-o"), prepared.clip.skeleton.joint_count(),
             prepared.clip.motion.frame_count, prepared.clip.motion.fps);
  return 0;
}

int run_augment(int argc, char** argv) {
  CommandLine cli("nec augment",
                  "Write a rig-augmented copy of a BVH file. Kinds: rest (a random frame becomes the rest pose),\n"
                  "length (bone lengths x0.8-1.2 per body part, left = right), joints (remove or subdivide joints\n"
                  "at random), remove (remove distal or zero-length joints), subdivide (insert joints into bones),\n"
                  "axes (the joint-orient convention of Maya / MotionBuilder exports: every joint's +X along its\n"
                  "bone, the rest pose a straight line), axes-random (a random frame per joint).\n"
                  "Every kind keeps the world positions of the joints it keeps, except length.");
  cli.positional("IN", "input BVH file or rigged asset");
  cli.option("--kind", "KIND", "rest", "rest | length | joints | remove | subdivide | axes | axes-random");
  cli.option("--seed", "N", "0", "random seed; the same seed gives the same rig");
  cli.option("-o", "OUT.bvh", "", "output BVH file", true);
  cli.example("nec augment walk.bvh --kind length --seed 3 -o walk_long_legs.bvh");
  if (!cli.parse(argc, argv)) return 0;
  const std::string kind_name = cli.value("--kind");
  SplitMix64 rng(static_cast<uint64_t>(cli.integer("--seed")));
  // Joint axes are not a training augmentation: preprocessing takes every convention to the canonical rest.
  const bool axes = kind_name == "axes" || kind_name == "axes-random";
  AugmentKind kind = AugmentKind::RestPose;
  if (kind_name == "joints") {
    kind = rng.chance(0.5) ? AugmentKind::JointRemoval : AugmentKind::Subdivision;
  } else if (!axes) {
    try {
      kind = augment_kind_from_string(kind_name);
    } catch (const std::invalid_argument&) {
      throw UsageError("--kind must be rest, length, joints, remove, subdivide, axes or axes-random, got '" +
                       kind_name + "'");
    }
  }
  const std::string path = cli.positional_value("IN");
  const Clip clip = read_clip(path);
  std::vector<std::string> canonical;
  for (const std::string& name : clip.skeleton.names) canonical.push_back(canonical_joint_name(name));
  const Clip out = axes ? reorient_joint_axes(clip, kind_name == "axes" ? JointAxes::BonesAlongX : JointAxes::Random, rng)
                        : augment(clip, kind, canonical, rng);
  write_bvh(cli.value("-o"), out.skeleton, out.motion);
  fmt::print("wrote {} ({} -> {} joints, {} frames)\n", cli.value("-o"), clip.skeleton.joint_count(),
             out.skeleton.joint_count(), out.motion.frame_count);
  return 0;
}

}  // namespace nec::app
