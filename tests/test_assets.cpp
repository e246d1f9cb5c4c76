// Rigged assets through assimp: a glTF written here with known world joint
// positions, the real assets of Debian's assimp-testmodels, and the format
// registry (FILE#ANIMATION, unknown types, folders of mixed files).
#include "nec/assets/asset_reader.h"
#include "nec/corpus/augment.h"
#include "nec/motion/clip_file.h"
#include "nec/corpus/corpus.h"
#include "nec/motion/error.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"

#include "test_support.h"

#include <assimp/Importer.hpp>
#include <assimp/scene.h>

#include <cmath>
#include <cstring>
#include <filesystem>

namespace nec {
namespace {

namespace fs = std::filesystem;

const std::string kModels = "/usr/share/assimp/models";

class AssetTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { assets::register_asset_formats(); }
};

std::string base64(const std::vector<float>& values) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> bytes(values.size() * sizeof(float));
  std::memcpy(bytes.data(), values.data(), bytes.size());
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned v = bytes[i] << 16 | (i + 1 < bytes.size() ? bytes[i + 1] << 8 : 0) |
                       (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += kAlphabet[v >> 18 & 63];
    out += kAlphabet[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kAlphabet[v >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[v & 63] : '=';
  }
  return out;
}

// An "Armature" node scaled 2x above a chain root -> mid -> tip, each 1 unit
// above its parent. Animation "bend" turns root and mid from 0 to 90 degrees
// about +Z over one second; "wave" turns mid alone.
std::string bending_chain_gltf() {
  const float s = static_cast<float>(std::sqrt(0.5));
  const std::vector<float> data{0, 1, 0, 0, 0, 1, 0, 0, s, s};  // times (0, 1 s); rotations xyzw: identity, 90° about Z
  return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"name": "Armature", "scale": [2, 2, 2], "children": [1]},
            {"name": "root", "translation": [0, 1, 0], "children": [2]},
            {"name": "mid", "translation": [0, 1, 0], "children": [3]},
            {"name": "tip", "translation": [0, 1, 0]}],
  "animations": [
    {"name": "bend", "samplers": [{"input": 0, "output": 1, "interpolation": "LINEAR"}],
     "channels": [{"sampler": 0, "target": {"node": 1, "path": "rotation"}},
                  {"sampler": 0, "target": {"node": 2, "path": "rotation"}}]},
    {"name": "wave", "samplers": [{"input": 0, "output": 1, "interpolation": "LINEAR"}],
     "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
                {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC4"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 32}],
  "buffers": [{"byteLength": 40, "uri": "data:application/octet-stream;base64,)" +
         base64(data) + R"("}]})";
}

void expect_near(const Vec3& actual, const Vec3& expected, const std::string& what) {
  EXPECT_LT((actual - expected).norm(), 1e-5) << what << ": " << actual.transpose() << " vs " << expected.transpose();
}

TEST_F(AssetTest, GltfChainKeepsItsWorldJointPositions) {
  testing::TempDir dir;
  const std::string file = dir.write("chain.gltf", bending_chain_gltf());
  const std::vector<Clip> clips = read_clips(file);
  ASSERT_EQ(clips.size(), 2u);
  EXPECT_EQ(clips[0].name, "bend");
  EXPECT_EQ(clips[1].name, "wave");
  const Clip& bend = clips[0];
  // The armature: the two moving nodes; "Armature" above is baked in, "tip" is an end site.
  ASSERT_EQ(bend.skeleton.joint_count(), 2);
  EXPECT_EQ(bend.skeleton.names[0], "root");
  EXPECT_EQ(bend.skeleton.names[1], "mid");
  ASSERT_EQ(bend.skeleton.end_sites.size(), 1u);
  EXPECT_EQ(bend.motion.frame_count, 31);  // one second at 30 fps, both ends
  EXPECT_DOUBLE_EQ(bend.motion.fps, 30.0);
  const Pose pose = forward_kinematics(bend.skeleton, bend.motion);
  const std::vector<Vec3> tips = end_site_positions(bend.skeleton, pose);
  const double r = std::sqrt(0.5);
  auto at = [&](int frame, int joint) { return pose.positions[static_cast<size_t>(frame) * 2 + joint]; };
  expect_near(at(0, 0), {0, 2, 0}, "root at 0 s");
  expect_near(at(0, 1), {0, 4, 0}, "mid at 0 s");
  expect_near(tips[0], {0, 6, 0}, "tip at 0 s");
  expect_near(at(15, 1), {-2 * r, 2 + 2 * r, 0}, "mid at 0.5 s");  // root turned 45°
  expect_near(tips[15], {-2 * r - 2, 2 + 2 * r, 0}, "tip at 0.5 s");  // 90° in all
  expect_near(at(30, 1), {-2, 2, 0}, "mid at 1 s");
  expect_near(tips[30], {-2, 0, 0}, "tip at 1 s");
  // Offsets in world units with world-aligned rest frames, as BVH.
  expect_near(bend.skeleton.offsets[1], {0, 2, 0}, "mid's offset");
}

TEST_F(AssetTest, AnimationChosenByNameOrFirstWithAWarning) {
  testing::TempDir dir;
  const std::string file = dir.write("chain.gltf", bending_chain_gltf());
  const Clip wave = read_clip(file + "#wave");
  EXPECT_EQ(wave.name, "wave");
  const Pose pose = forward_kinematics(wave.skeleton, wave.motion);
  expect_near(end_site_positions(wave.skeleton, pose)[30], {-2, 4, 0}, "tip of the wave at 1 s");
  const Clip first = read_clip(file);
  EXPECT_EQ(first.name, "bend");
  ASSERT_FALSE(first.warnings.empty());
  EXPECT_NE(first.warnings.back().find("'wave'"), std::string::npos) << first.warnings.back();
  try {
    read_clips(file + "#run");
    FAIL() << "no animation 'run'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no animation named 'run' (the file has 'bend', 'wave')"), std::string::npos)
        << e.what();
  }
}

TEST_F(AssetTest, SamplingRateFollowsTheOption) {
  testing::TempDir dir;
  const std::string file = dir.write("chain.gltf", bending_chain_gltf());
  ClipReadOptions options;
  options.fps = 60;
  const Clip bend = read_clip(file + "#bend", options);
  EXPECT_EQ(bend.motion.frame_count, 61);
  EXPECT_DOUBLE_EQ(bend.motion.fps, 60.0);
}

TEST_F(AssetTest, UnknownTypeAndMissingFileAreInputErrors) {
  testing::TempDir dir;
  const std::string text = dir.write("notes.txt", "hello");
  EXPECT_THROW(read_clips(text), InputError);
  EXPECT_THROW(read_clips(dir / "missing.fbx"), InputError);
  const std::string broken = dir.write("broken.gltf", "{\"asset\": ");
  try {
    read_clips(broken);
    FAIL() << "a broken glTF";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(broken), std::string::npos) << e.what();
  }
}

TEST_F(AssetTest, RealAssetsWithArmatureAnimation) {
  if (!fs::exists(kModels + "/X/Testwuson.X")) GTEST_SKIP() << "assimp-testmodels is not installed";
  // Three animations in one DirectX file, one clip each, named after them.
  const std::vector<Clip> wuson = read_clips(kModels + "/X/Testwuson.X");
  ASSERT_EQ(wuson.size(), 3u);
  EXPECT_EQ(wuson[0].name, "Wuson_Run");
  EXPECT_EQ(wuson[1].name, "Wuson_Walk");
  EXPECT_EQ(wuson[2].name, "Wuson_Bind");
  EXPECT_EQ(wuson[1].motion.frame_count, 109);  // 17280 ticks at 4800 per second = 3.6 s at 30 fps
  EXPECT_EQ(wuson[0].skeleton.joint_count(), 38);
  // Blender-made FBX: the armature object above the bones is baked in; bone tips become end sites.
  const Clip bones = read_clip(kModels + "/FBX/huesitos.fbx");
  EXPECT_EQ(bones.name, "Armature|Action");
  EXPECT_EQ(bones.skeleton.joint_count(), 9);
  EXPECT_EQ(bones.skeleton.names[0], "Bone");
  EXPECT_EQ(bones.skeleton.end_sites.size(), 2u);
  EXPECT_GT(bones.motion.frame_count, 40);
  // A human whose animation keeps its bone lengths: preprocessing takes it (one joint's animated offset
  // differs from its bind pose and is folded).
  const Clip human = read_clip(kModels + "/X/BCN_Epileptic.X");
  EXPECT_EQ(human.skeleton.joint_count(), 54);
  int moved = 0;
  for (int j = 1; j < human.skeleton.joint_count(); ++j) moved += human.skeleton.channels[j].has_position();
  EXPECT_LE(moved, 1);
  const PreparedClip prepared = preprocess(human, "BCN_Epileptic.X");
  EXPECT_TRUE(prepared.report.accepted()) << prepared.report.rejection;
}

TEST_F(AssetTest, AssetsWithoutArmatureSaySo) {
  if (!fs::exists(kModels + "/FBX/spider.fbx")) GTEST_SKIP() << "assimp-testmodels is not installed";
  for (const std::string file : {"/FBX/spider.fbx", "/Collada/human.zae"}) {
    try {
      read_clips(kModels + file);
      FAIL() << file << " has no armature";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("no armature"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
    }
  }
}

TEST_F(AssetTest, CorpusFoldersTakeAssetsOneEntryPerAnimation) {
  testing::TempDir dir;
  dir.write("mixed/chain.gltf", bending_chain_gltf());
  dir.write("mixed/notes.txt", "not motion");
  const std::vector<CorpusFile> files = find_corpus_files({dir / "mixed"});
  ASSERT_EQ(files.size(), 1u);
  CorpusOptions options;
  options.kinematic_captions = false;
  const CorpusResult corpus = load_corpus(files, options);
  ASSERT_EQ(corpus.entries.size(), 2u);
  EXPECT_EQ(corpus.entries[0].id, files[0].path + "#bend");
  EXPECT_EQ(corpus.entries[1].id, files[0].path + "#wave");
}

// Scene contents a user's asset must keep: meshes, skinned bones, materials.
struct SceneCounts {
  unsigned meshes = 0, bones = 0, materials = 0, animations = 0;
};

SceneCounts count_scene(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, 0);
  EXPECT_NE(scene, nullptr) << path << ": " << importer.GetErrorString();
  SceneCounts out;
  if (scene == nullptr) return out;
  out.meshes = scene->mNumMeshes;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) out.bones += scene->mMeshes[m]->mNumBones;
  out.materials = scene->mNumMaterials;
  out.animations = scene->mNumAnimations;
  return out;
}

TEST_F(AssetTest, MotionWrittenOntoACopyOfTheAssetReadsBackTheSame) {
  if (!fs::exists(kModels + "/X/Testwuson.X")) GTEST_SKIP() << "assimp-testmodels is not installed";
  // A DirectX file with three animations; a Blender FBX in centimetres under an armature scaled x100.
  for (const std::string& asset : {kModels + "/X/Testwuson.X", kModels + "/FBX/huesitos.fbx"}) {
    SCOPED_TRACE(asset);
    Clip clip = read_clip(asset);
    // A motion the asset does not hold: its first animation turned by 90 degrees and moved 2 m.
    for (int t = 0; t < clip.motion.frame_count; ++t) {
      clip.motion.rotation(t, 0) = axis_rotation(1, 90.0) * clip.motion.rotation(t, 0);
      clip.motion.translation(t, 0) = axis_rotation(1, 90.0) * clip.motion.translation(t, 0) + Vec3(2, 0, 0);
    }
    testing::TempDir dir;
    const std::string out = dir / "turned.glb";
    write_clip(out, clip, asset, "turned");
    const std::vector<Clip> clips = read_clips(out);
    const SceneCounts source = count_scene(asset), copy = count_scene(out);
    ASSERT_EQ(clips.size(), source.animations + 1);  // the new animation first, then the asset's own
    EXPECT_EQ(clips[0].name, "turned");
    const Clip& back = clips[0];
    ASSERT_EQ(back.skeleton.names, clip.skeleton.names);
    ASSERT_EQ(back.motion.frame_count, clip.motion.frame_count);
    const Pose written = forward_kinematics(clip.skeleton, clip.motion);
    const Pose read = forward_kinematics(back.skeleton, back.motion);
    double worst = 0.0;
    for (size_t i = 0; i < written.positions.size(); ++i) {
      worst = std::max(worst, (written.positions[i] - read.positions[i]).norm());
    }
    EXPECT_LT(worst, 1e-4 * clip.skeleton.diameter());  // metres and +Y up both ways
    EXPECT_EQ(copy.meshes, source.meshes);
    EXPECT_EQ(copy.bones, source.bones);
    EXPECT_GE(copy.materials, source.materials);
  }
}

// The same motion with another rest pose (every joint's world position kept): its rotations are turns from a
// different rest, which would bend the asset's mesh.
TEST_F(AssetTest, MotionOnAnotherRestPoseIsRefused) {
  if (!fs::exists(kModels + "/X/Testwuson.X")) GTEST_SKIP() << "assimp-testmodels is not installed";
  const std::string asset = kModels + "/X/Testwuson.X";
  const Clip walk = read_clip(asset + "#Wuson_Walk");
  testing::TempDir dir;
  try {
    write_clip(dir / "bent.glb", reset_rest_pose_to_frame(walk, 50), asset, "bent");
    FAIL() << "another rest pose was written";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rest pose is not this asset's"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir / "bent.glb"));
}

TEST_F(AssetTest, OutputsNecCannotWriteAreRefusedFirst) {
  testing::TempDir dir;
  const std::string gltf = dir.write("chain.gltf", bending_chain_gltf());
  EXPECT_NO_THROW(check_clip_output(dir / "out.glb", gltf));
  EXPECT_NO_THROW(check_clip_output(dir / "out.bvh", gltf));
  EXPECT_NO_THROW(check_clip_output(dir / "out.glb", gltf + "#wave"));
  for (const auto& [out, target] : std::vector<std::pair<std::string, std::string>>{
           {dir / "out.fbx", gltf}, {dir / "out.glb", dir / "walk.bvh"}, {dir / "out.glb", ""}}) {
    try {
      check_clip_output(out, target);
      FAIL() << out << " onto '" << target << "'";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(out), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace
}  // namespace nec
