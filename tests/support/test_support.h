// Shared helpers for the tests: random rotations and trees, data paths.
#pragma once

#include "nec/motion/motion.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace nec::testing {

// Directory of the Debian CMU BVH files (assimp-testmodels).
std::string cmu_bvh_dir();
// ../shared/data, or "" when absent.
std::string shared_data_dir();
// All *.bvh below `dir`, sorted.
std::vector<std::string> bvh_files_under(const std::string& dir);

Quat random_rotation(std::mt19937& rng);
// A random tree of `joints` joints with random offsets and channel layouts.
Skeleton random_skeleton(std::mt19937& rng, int joints);
// Random local rotations (and root translation) for every frame.
Motion random_motion(std::mt19937& rng, const Skeleton& skeleton, int frames);

// A fresh folder under the system temp folder, removed with everything in it
// when the object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // Full path of `relative` inside the folder.
  std::string operator/(const std::string& relative) const { return (path_ / relative).string(); }
  // Writes `text` to `relative` (creating folders); returns the full path.
  std::string write(const std::string& relative, const std::string& text) const;

 private:
  std::filesystem::path path_;
};

// A test suite whose tests share one folder, made before its first test
// (SetUpTestSuite of the derived suite fills it) and removed after its last,
// and a folder of each test's own.
class SharedFolderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  static const TempDir& shared_folder() { return *shared_; }
  // Full path of `relative` in the shared folder / in this test's folder.
  static std::string shared(const std::string& relative) { return *shared_ / relative; }
  std::string path(const std::string& relative) const { return dir_ / relative; }

  TempDir dir_;

 private:
  static std::unique_ptr<TempDir> shared_;
};

// `part` occurs in `text`.
inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// The built `nec` binary run with `arguments` (a shell command line), stdout and stderr together.
struct CommandResult {
  int exit_code = -1;
  std::string output;
};
CommandResult run_nec(const std::string& arguments);
// What the command-line tests of the text models share: `nec zoo` (9 creatures of `clips_per_creature` 2-s clips,
// the spider held out, `seed`) into d/zoo, prepared into d/cache with the held-out spiders as the dataset
// zoo_held_out (`prepare_options` added), a caption piece model of 150 pieces in d/spm.model and a tiny OwO
// encoder without names in d/owo. A failing step fails the calling test (check HasFatalFailure()).
void make_captioned_zoo(const TempDir& d, int clips_per_creature, int seed, const std::string& prepare_options = "");

// The last line of `output` that starts with `prefix` ("" if none), e.g. the last "step 4/4" of a training log.
std::string last_line_starting(const std::string& output, const std::string& prefix);

// Stretches the root's horizontal travel about its frame-0 position by `factor`: above 1 the body outruns its
// legs and planted feet slide.
void stretch_root_travel(Motion& motion, double factor);

// Largest distance between corresponding positions of two pose sets.
double max_position_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b);

// Largest angle (radians) between corresponding joint rotations of two motions; infinity if their sizes differ.
double largest_rotation_difference(const Motion& a, const Motion& b);

}  // namespace nec::testing
