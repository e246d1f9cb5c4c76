// Whole-file helpers: atomic writes and tree removal.
#include "nec/motion/files.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace nec {
namespace {

namespace fs = std::filesystem;

void touch(const fs::path& path) { std::ofstream(path) << "x"; }

TEST(Files, RemoveTreeRemovesNestedDirectoriesButNotWhatLinksPointAt) {
  testing::TempDir dir;
  const fs::path root = fs::path(dir.path()) / "tree";
  fs::create_directories(root / "a" / "b");
  touch(root / "top.txt");
  touch(root / "a" / "b" / "deep.txt");
  const fs::path outside = fs::path(dir.path()) / "outside";
  fs::create_directories(outside);
  touch(outside / "kept.txt");
  fs::create_directory_symlink(outside, root / "a" / "link");

  EXPECT_EQ(remove_tree(root.string()), "");
  EXPECT_FALSE(fs::exists(root));
  EXPECT_TRUE(fs::exists(outside / "kept.txt"));  // the link went, not its target

  touch(root.string() + ".file");
  EXPECT_EQ(remove_tree(root.string() + ".file"), "");  // a plain file
  EXPECT_FALSE(fs::exists(root.string() + ".file"));
  EXPECT_EQ(remove_tree(root.string()), "");  // missing: nothing to do
}

}  // namespace
}  // namespace nec
