// Whole-file reading and atomic writing (temp file + rename, so a failed
// write never leaves a half-written output behind).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nec {

// Throws InputError naming the file when it cannot be read or exceeds max_bytes.
std::string read_file(const std::string& path, size_t max_bytes = size_t{1} << 32);
// Writes `contents` to `path` through a temporary file in the same directory,
// flushed to disk (fsync) before it is renamed into place, and the directory
// after: a crash leaves the old file or the new one. Throws std::runtime_error
// naming the file on failure.
void write_file_atomic(const std::string& path, std::string_view contents);
// fsync of a file or a directory; throws std::runtime_error naming it on failure.
void sync_to_disk(const std::string& path);

// Removes a file or a whole directory tree; symbolic links are removed, never
// followed; a missing path is no error. Returns "" on success, else why the
// first entry that could not be removed stayed. Use it instead of
// std::filesystem::remove_all: in a process that loads LibTorch 2.x (pip
// builds), that symbol binds to libtorch.so's own copy, which crashes.
std::string remove_tree(const std::string& path);

// A whole file mapped read-only into memory. Copies share the mapping; the
// last one unmaps it. An empty file gives an empty mapping.
class MappedFile {
 public:
  MappedFile() = default;
  // `populate` faults every page in now (faster than one by one on first use).
  // Throws InputError naming the file when it cannot be opened or mapped.
  static MappedFile open(const std::string& path, bool populate = false);
  // The files end to end in one mapping, as if they were one file; none where
  // a file but the last does not fill whole pages (read them instead). Throws
  // InputError naming a file that cannot be opened or mapped.
  static std::optional<MappedFile> open_joined(const std::vector<std::string>& paths);

  const unsigned char* data() const { return data_; }
  size_t size() const { return size_; }

 private:
  std::shared_ptr<const void> owner_;
  const unsigned char* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace nec
