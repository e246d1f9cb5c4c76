// Whole-file helpers: atomic writes, tree removal and files mapped end to end.
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

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

// Files that fill whole pages and a last one of any size read as one; a file in front that does not fill its
// pages is refused (the caller reads instead); a missing file is named.
TEST(Files, JoinedMappingReadsTheFilesEndToEnd) {
  testing::TempDir dir;
  const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
  std::string a(2 * page, 'a'), b(page, 'b');
  a[5] = 'x';
  b[page - 1] = 'y';
  const std::string c = "the last file, of any size";
  const std::string pa = dir / "a", pb = dir / "b", pc = dir / "c";
  write_file_atomic(pa, a);
  write_file_atomic(pb, b);
  write_file_atomic(pc, c);
  const std::optional<MappedFile> joined = MappedFile::open_joined({pa, pb, pc});
  ASSERT_TRUE(joined.has_value());
  ASSERT_EQ(joined->size(), a.size() + b.size() + c.size());
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(joined->data()), joined->size()), a + b + c);

  EXPECT_FALSE(MappedFile::open_joined({pc, pa}).has_value());  // c does not fill a page
  try {
    MappedFile::open_joined({pa, dir / "missing"});
    ADD_FAILURE() << "a missing file was mapped";
  } catch (const InputError& e) {
    EXPECT_TRUE(testing::contains(e.what(), "missing")) << e.what();
  }
}

}  // namespace
}  // namespace nec
