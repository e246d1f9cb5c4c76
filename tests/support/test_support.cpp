// Shared helpers for the tests.
#include "test_support.h"

#include "nec/motion/rotations.h"

#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace nec::testing {

std::string cmu_bvh_dir() { return NEC_CMU_BVH_DIR; }

void make_captioned_zoo(const TempDir& d, int clips_per_creature, int seed, const std::string& prepare_options) {
  const CommandResult zoo = run_nec("zoo --out " + d / "zoo" + " --creatures 9 --clips-per-creature " +
                                    std::to_string(clips_per_creature) + " --seconds 2 --seed " + std::to_string(seed) +
                                    " --hold-out spider --quiet");
  ASSERT_EQ(zoo.exit_code, 0) << zoo.output;
  const CommandResult prepare = run_nec("prepare zoo=" + d / "zoo/seen" + " zoo_held_out=" + d / "zoo/held_out" +
                                        " --hold-out-dataset zoo_held_out -o " + d / "cache" + " --quiet " + prepare_options);
  ASSERT_EQ(prepare.exit_code, 0) << prepare.output;
  const CommandResult pieces =
      run_nec("text train-tokenizer --data " + d / "cache" + " -o " + d / "spm.model" + " --vocab-size 150");
  ASSERT_EQ(pieces.exit_code, 0) << pieces.output;
  d.write("owo.json", R"({"encoder": {"name_dim": 0, "dim": 16, "layers": 1, "heads": 2, "edge_dim": 8},
    "names": false, "batch_size": 4, "steps": 2, "log_every": 1, "validate_every": 0, "checkpoint_every": 0})");
  const CommandResult owo =
      run_nec("train owo --config " + d / "owo.json" + " --data " + d / "cache" + " --out " + d / "owo" + " --threads 1");
  ASSERT_EQ(owo.exit_code, 0) << owo.output;
}

CommandResult run_nec(const std::string& arguments) {
  const std::string command = std::string(NEC_BINARY_DIR) + "/apps/nec " + arguments + " 2>&1";
  CommandResult run;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return run;
  std::array<char, 4096> buffer{};
  size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) run.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

std::string last_line_starting(const std::string& output, const std::string& prefix) {
  std::string found;
  size_t start = 0;
  while (start < output.size()) {
    size_t end = output.find('\n', start);
    if (end == std::string::npos) end = output.size();
    const std::string line = output.substr(start, end - start);
    if (line.rfind(prefix, 0) == 0) found = line;
    start = end + 1;
  }
  return found;
}

std::string shared_data_dir() {
  const std::string dir = NEC_SHARED_DATA_DIR;
  return std::filesystem::is_directory(dir) ? dir : std::string();
}

std::vector<std::string> bvh_files_under(const std::string& dir) {
  std::vector<std::string> out;
  if (dir.empty() || !std::filesystem::is_directory(dir)) return out;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".bvh") out.push_back(entry.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

Quat random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Quat q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized();
}

Skeleton random_skeleton(std::mt19937& rng, int joints) {
  std::uniform_real_distribution<double> offset(-1.0, 1.0);
  std::uniform_int_distribution<int> order(0, 5);
  Skeleton s;
  s.add_joint("root", -1, Vec3::Zero(), ChannelLayout::position_rotations(static_cast<EulerOrder>(order(rng))));
  for (int j = 1; j < joints; ++j) {
    std::uniform_int_distribution<int> parent(0, j - 1);
    s.add_joint("joint" + std::to_string(j), parent(rng), Vec3(offset(rng), offset(rng), offset(rng)),
                ChannelLayout::rotations(static_cast<EulerOrder>(order(rng))));
  }
  for (int leaf : s.leaves()) s.end_sites.push_back({leaf, Vec3(offset(rng), offset(rng), offset(rng))});
  // List joints as a BVH file would, so that write/read keeps indices.
  Clip clip{s, Motion::rest(s, 0, 30.0), {}};
  permute_joints(clip, s.depth_first_order());
  return clip.skeleton;
}

Motion random_motion(std::mt19937& rng, const Skeleton& skeleton, int frames) {
  std::uniform_real_distribution<double> position(-2.0, 2.0);
  Motion m = Motion::rest(skeleton, frames, 30.0);
  for (int t = 0; t < frames; ++t) {
    for (int j = 0; j < skeleton.joint_count(); ++j) m.rotation(t, j) = random_rotation(rng);
    m.translation(t, 0) = Vec3(position(rng), position(rng), position(rng));
  }
  return m;
}

std::unique_ptr<TempDir> SharedFolderTest::shared_;

void SharedFolderTest::SetUpTestSuite() { shared_ = std::make_unique<TempDir>(); }

void SharedFolderTest::TearDownTestSuite() { shared_.reset(); }

TempDir::TempDir() {
  std::random_device entropy;
  path_ = std::filesystem::temp_directory_path() / ("nec_test_" + std::to_string(entropy()) + std::to_string(entropy()));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string TempDir::write(const std::string& relative, const std::string& text) const {
  const std::filesystem::path file = path_ / relative;
  std::filesystem::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << text;
  return file.string();
}

void stretch_root_travel(Motion& motion, double factor) {
  if (motion.frame_count == 0) return;
  const Vec3 start = motion.translation(0, 0);
  for (int t = 0; t < motion.frame_count; ++t) {
    Vec3& root = motion.translation(t, 0);
    root.x() = start.x() + factor * (root.x() - start.x());
    root.z() = start.z() + factor * (root.z() - start.z());
  }
}

double max_position_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a[i] - b[i]).norm());
  return worst;
}

double largest_rotation_difference(const Motion& a, const Motion& b) {
  if (a.rotations.size() != b.rotations.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (size_t i = 0; i < a.rotations.size(); ++i) worst = std::max(worst, geodesic_distance(a.rotations[i], b.rotations[i]));
  return worst;
}

}  // namespace nec::testing
