// nec info | convert | normalize | augment: single-file BVH commands.
#include "command_line.h"
#include "commands.h"

#include "nec/motion/augment.h"
#include "nec/motion/bvh.h"
#include "nec/motion/names.h"
#include "nec/motion/preprocess.h"
#include "nec/motion/rest_pose.h"

#include <fmt/format.h>

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

EulerOrder parse_order_option(const std::string& text) {
  const auto order = parse_euler_order(text);
  if (!order) throw UsageError("--order must be one of XYZ XZY YXZ YZX ZXY ZYX, got '" + text + "'");
  return *order;
}

}  // namespace

int run_info(int argc, char** argv) {
  CommandLine cli("nec info", "Print a BVH file's skeleton and motion summary.");
  cli.positional("FILE.bvh", "BVH file to describe");
  cli.flag("--no-tree", "omit the joint tree");
  cli.flag("--json", "print one JSON line: joints, end_sites, frames, fps, diameter");
  cli.example("nec info /usr/share/assimp/models/BVH/01_01.bvh");
  if (!cli.parse(argc, argv)) return 0;
  const std::string path = cli.positional_value("FILE.bvh");
  const Clip clip = read_bvh(path);
  const Skeleton& s = clip.skeleton;
  const Motion& m = clip.motion;
  if (cli.is_set("--json")) {
    fmt::print("{{\"joints\": {}, \"end_sites\": {}, \"frames\": {}, \"fps\": {:.9g}, \"diameter\": {:.9g}}}\n",
               s.joint_count(), s.end_sites.size(), m.frame_count, m.fps, s.diameter());
    return 0;
  }
  fmt::print("file      {}\n", path);
  fmt::print("joints    {} ({} end sites, {} leaves, max depth {})\n", s.joint_count(), s.end_sites.size(),
             s.leaves().size(), [&] {
               int d = 0;
               for (int j = 0; j < s.joint_count(); ++j) d = std::max(d, s.depth(j));
               return d;
             }());
  fmt::print("frames    {} at {:.6g} fps ({:.2f} s)\n", m.frame_count, m.fps, m.duration_seconds());
  fmt::print("diameter  {:.6g} (longest root-to-leaf chain, file units)\n", s.diameter());
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
  CommandLine cli("nec convert", "Read a BVH file and write it back, unchanged or with another Euler order.");
  cli.positional("IN.bvh", "input BVH file");
  cli.option("-o", "OUT.bvh", "", "output BVH file", true);
  cli.option("--order", "ORDER", "keep", "Euler order of every rotated joint: XYZ XZY YXZ YZX ZXY ZYX, or keep");
  cli.example("nec convert walk.bvh -o walk_xyz.bvh --order XYZ");
  if (!cli.parse(argc, argv)) return 0;
  BvhWriteOptions options;
  if (cli.value("--order") != "keep") options.euler_order = parse_order_option(cli.value("--order"));
  const Clip clip = read_bvh(cli.positional_value("IN.bvh"));
  write_bvh(cli.value("-o"), clip.skeleton, clip.motion, options);
  fmt::print("wrote {} ({} joints, {} frames)\n", cli.value("-o"), clip.skeleton.joint_count(), clip.motion.frame_count);
  return 0;
}

int run_normalize(int argc, char** argv) {
  CommandLine cli("nec normalize",
                  "Apply the unified preprocessing (dummy root merge, root-only translation, unit diameter, +Y up,\n"
                  "frame 0 facing +Z, corpus frame rate, the canonical rest pose: the clip's mean pose with\n"
                  "world-aligned joint frames) and write the result; prints what was changed.");
  cli.positional("IN.bvh", "input BVH file");
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
  const std::string path = cli.positional_value("IN.bvh");
  const PreparedClip prepared = preprocess(read_bvh(path), path, options);
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
  cli.positional("IN.bvh", "input BVH file");
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
  const std::string path = cli.positional_value("IN.bvh");
  const Clip clip = read_bvh(path);
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
