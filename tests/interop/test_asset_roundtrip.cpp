// Assets against Blender 3.4, joint by joint and frame by frame:
// - BVH -> Blender (import, export FBX and GLB) -> nec's asset reader: the
//   same world joint positions as the BVH;
// - motion written by nec onto a copy of an asset (GLB) -> Blender's glTF
//   importer: the mesh, its skin and the animation, bones where nec's FK puts them.
// Needs blender and numpy for its glTF importer (scripts/test.sh and scripts/interop.sh install them); skipped
// without blender.
#include "nec/assets/asset_reader.h"
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"

#include "test_support.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace nec {
namespace {

namespace fs = std::filesystem;

// World positions of the joints named in `names`, per frame, read by name from `clip`.
std::vector<Vec3> positions_by_name(const Clip& clip, const std::vector<std::string>& names) {
  const Pose pose = forward_kinematics(clip.skeleton, clip.motion);
  std::vector<Vec3> out;
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    for (const std::string& name : names) {
      const int j = clip.skeleton.find(name);
      out.push_back(j < 0 ? Vec3::Constant(NAN) : pose.position(t, j));
    }
  }
  return out;
}

bool have_blender();

TEST(AssetRoundTrip, BlenderFbxAndGlbKeepTheWorldJointPositions) {
  if (!have_blender()) GTEST_SKIP() << "blender is not installed (scripts/interop.sh installs it)";
  assets::register_asset_formats();
  testing::TempDir dir;
  std::vector<std::string> sources;
  for (const char* name : {"01_01.bvh", "Boxing_Toes.bvh"}) {
    const std::string path = testing::cmu_bvh_dir() + "/" + name;
    if (fs::exists(path)) sources.push_back(path);
  }
  const zoo::Creature dragon = zoo::make_creature(zoo::BodyPlan::Dragon, 5);
  zoo::MotionSpec spec;
  spec.action = zoo::Action::Walk;
  spec.speed = zoo::typical_speed(dragon, spec.action);
  spec.seconds = 2.0;
  sources.push_back(dir / "dragon_walk.bvh");
  write_bvh(sources.back(), dragon.skeleton, zoo::synthesize_motion(dragon, spec).motion);

  std::string command = "blender -b --factory-startup --python-exit-code 1 --python " +
                        std::string(NEC_SOURCE_DIR) + "/tests/interop/blender_export_assets.py -- " + dir.path().string();
  for (const std::string& s : sources) command += " " + s;
  command += " > " + (dir / "blender.log") + " 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << "blender failed; its log: " << dir / "blender.log";

  for (const std::string& source : sources) {
    const Clip bvh = read_bvh(source);
    const std::vector<Vec3> expected = positions_by_name(bvh, bvh.skeleton.names);
    const double diameter = bvh.skeleton.diameter();
    for (const char* ext : {".fbx", "_zup.fbx", ".glb"}) {
      const std::string asset = dir / (fs::path(source).stem().string() + ext);
      ClipReadOptions options;
      options.fps = bvh.motion.fps;  // Blender keyed the BVH's frames at its rate
      Clip read = read_clip(asset, options);
      // Blender's BVH import ends the scene one frame after the file's last: the export holds that frame.
      ASSERT_GE(read.motion.frame_count, bvh.motion.frame_count) << asset;
      ASSERT_LE(read.motion.frame_count, bvh.motion.frame_count + 1) << asset;
      read.motion = read.motion.slice(0, bvh.motion.frame_count);
      const std::vector<Vec3> actual = positions_by_name(read, bvh.skeleton.names);
      double worst = 0.0;
      size_t where = 0;
      for (size_t i = 0; i < expected.size(); ++i) {
        const double d = (actual[i] - expected[i]).norm();
        if (d > worst) worst = d, where = i;
      }
      const int joints = bvh.skeleton.joint_count();
      std::printf("%s: %d joints, %d frames; largest joint position difference %.3g (%.3g diameters, frame %d, %s)\n",
                  asset.c_str(), joints, bvh.motion.frame_count, worst, worst / diameter,
                  static_cast<int>(where / joints), bvh.skeleton.names[where % joints].c_str());
      // Measured (docs/assets.md): FBX ~1e-6 diameters; GLB up to 3e-4 on a 23-s CMU take (Blender's glTF root path).
      EXPECT_LT(worst / diameter, 1e-3) << asset;
    }
  }
}

bool have_blender() { return std::system("command -v blender >/dev/null 2>&1") == 0; }

TEST(AssetRoundTrip, BlenderImportsMotionWrittenOntoAnAsset) {
  if (!have_blender()) GTEST_SKIP() << "blender is not installed (scripts/interop.sh installs it)";
  assets::register_asset_formats();
  testing::TempDir dir;
  const std::string models = "/usr/share/assimp/models";
  for (const std::string& asset : {models + "/X/Testwuson.X", models + "/X/BCN_Epileptic.X", models + "/FBX/huesitos.fbx"}) {
    if (!fs::exists(asset)) GTEST_SKIP() << "assimp-testmodels is not installed";
    // The asset's own first animation, turned by 90 degrees and moved 1 m: a motion the file does not hold.
    Clip clip = read_clip(asset);
    for (int t = 0; t < clip.motion.frame_count; ++t) {
      clip.motion.rotation(t, 0) = axis_rotation(1, 90.0) * clip.motion.rotation(t, 0);
      clip.motion.translation(t, 0) = axis_rotation(1, 90.0) * clip.motion.translation(t, 0) + Vec3(1, 0, 0);
    }
    const std::string out = dir / (fs::path(asset).stem().string() + ".glb");
    write_clip(out, clip, asset, "nec_motion");
    const std::string table = out + ".tsv";
    const std::string command = "blender -b --factory-startup --python-exit-code 1 --python " +
                                std::string(NEC_SOURCE_DIR) + "/tests/interop/blender_read_glb.py -- " + out +
                                " nec_motion 30 " + table + " > " + out + ".log 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << "blender could not import " << out << "; its log: " << out << ".log";
    std::ifstream log(out + ".log");
    for (std::string line; std::getline(log, line);) {
      if (line.rfind("blender", 0) == 0) std::printf("%s: %s\n", out.c_str(), line.c_str());
    }
    const Pose pose = forward_kinematics(clip.skeleton, clip.motion);
    std::ifstream rows(table);
    double worst = 0.0;
    int compared = 0, frames = 0;
    std::set<std::string> unmatched;
    for (std::string line; std::getline(rows, line);) {
      std::istringstream fields(line);
      int frame = 0;
      std::string bone;
      Vec3 p;
      std::getline(fields >> frame >> std::ws, bone, '\t');
      fields >> p.x() >> p.y() >> p.z();
      const int j = clip.skeleton.find(bone);
      if (j < 0 || frame >= clip.motion.frame_count) {
        unmatched.insert(bone);
        continue;
      }
      worst = std::max(worst, (p - pose.position(frame, j)).norm());
      frames = std::max(frames, frame + 1);
      ++compared;
    }
    const double diameter = clip.skeleton.diameter();
    std::printf("%s: %d bone positions compared over %d frames; largest difference %.3g (%.3g diameters); "
                "%zu bones without a joint\n",
                out.c_str(), compared, frames, worst, worst / diameter, unmatched.size());
    EXPECT_EQ(frames, clip.motion.frame_count) << out;
    EXPECT_GT(compared, frames * (clip.skeleton.joint_count() - 2)) << out;
    EXPECT_LT(worst / diameter, 1e-3) << out;
  }
}

}  // namespace
}  // namespace nec
