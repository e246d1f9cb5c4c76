// File reading and atomic writing.
#include "nec/motion/files.h"

#include "nec/motion/error.h"

#include <fcntl.h>
#include <ftw.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

namespace nec {

std::string read_file(const std::string& path, size_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, 0, "is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw InputError(path, 0, "cannot determine the file size");
  if (static_cast<size_t>(size) > max_bytes) {
    throw InputError(path, 0, "file is " + std::to_string(size) + " bytes, more than the limit of " +
                                  std::to_string(max_bytes));
  }
  std::string data(static_cast<size_t>(size), '\0');
  in.seekg(0);
  in.read(data.data(), size);
  if (!in) throw InputError(path, 0, "read failed");
  return data;
}

void write_file_atomic(const std::string& path, std::string_view contents) {
  const std::filesystem::path target(path);
  std::random_device entropy;
  const std::filesystem::path temp =
      target.parent_path() / ("." + target.filename().string() + ".tmp" + std::to_string(entropy()));
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write: " + std::strerror(errno));
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    out.flush();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temp, ignored);
      throw std::runtime_error(path + ": write failed: " + std::strerror(errno));
    }
  }
  std::error_code ec;
  try {
    sync_to_disk(temp.string());
  } catch (const std::runtime_error&) {
    std::filesystem::remove(temp, ec);
    throw;
  }
  std::filesystem::rename(temp, target, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temp, ignored);
    throw std::runtime_error(path + ": cannot move the written file into place: " + ec.message());
  }
  sync_to_disk(target.parent_path().empty() ? "." : target.parent_path().string());
}

void sync_to_disk(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(path + ": cannot open to flush it to disk: " + std::strerror(errno));
  const bool ok = ::fsync(fd) == 0;
  const int error = errno;
  ::close(fd);
  if (!ok) throw std::runtime_error(path + ": cannot flush to disk: " + std::strerror(error));
}

namespace {

// nftw's callback has no user data: the first failure of the walk under way.
thread_local std::string* g_remove_failure = nullptr;

int remove_entry(const char* path, const struct stat*, int, struct FTW*) {
  if (::remove(path) != 0 && errno != ENOENT && g_remove_failure->empty()) {
    *g_remove_failure = std::string(path) + ": cannot remove: " + std::strerror(errno);
  }
  return 0;  // go on: remove what can be removed
}

}  // namespace

std::string remove_tree(const std::string& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) {
    return errno == ENOENT ? "" : path + ": cannot remove: " + std::strerror(errno);
  }
  std::string failure;
  g_remove_failure = &failure;
  constexpr int kOpenDirectories = 32;
  // Children before their directory (FTW_DEPTH); links are not followed (FTW_PHYS).
  const int walked = ::nftw(path.c_str(), remove_entry, kOpenDirectories, FTW_DEPTH | FTW_PHYS);
  g_remove_failure = nullptr;
  if (walked != 0 && failure.empty()) failure = path + ": cannot remove: " + std::strerror(errno);
  return failure;
}

namespace {

// A descriptor of the regular file `path` and its size; InputError naming it otherwise.
int open_regular_file(const std::string& path, size_t& size) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    ::close(fd);
    throw InputError(path, 0, "not a regular file");
  }
  size = static_cast<size_t>(info.st_size);
  return fd;
}

}  // namespace

MappedFile MappedFile::open(const std::string& path, bool populate) {
  MappedFile out;
  const int fd = open_regular_file(path, out.size_);
  if (out.size_ == 0) {
    ::close(fd);
    return out;
  }
  int flags = MAP_PRIVATE;
#ifdef MAP_POPULATE
  if (populate) flags |= MAP_POPULATE;
#endif
  void* mapping = ::mmap(nullptr, out.size_, PROT_READ, flags, fd, 0);
  const int map_error = errno;
  ::close(fd);
  if (mapping == MAP_FAILED) throw InputError(path, 0, std::string("cannot map: ") + std::strerror(map_error));
  const size_t bytes = out.size_;
  out.owner_ = std::shared_ptr<const void>(mapping, [bytes](const void* p) { ::munmap(const_cast<void*>(p), bytes); });
  out.data_ = static_cast<const unsigned char*>(mapping);
  return out;
}

std::optional<MappedFile> MappedFile::open_joined(const std::vector<std::string>& paths) {
  struct Descriptors {  // closed on every way out
    std::vector<int> fds;
    ~Descriptors() {
      for (const int fd : fds) ::close(fd);
    }
  } files;
  const size_t page = static_cast<size_t>(::sysconf(_SC_PAGESIZE));
  std::vector<size_t> sizes(paths.size());
  size_t total = 0;
  for (size_t i = 0; i < paths.size(); ++i) {
    files.fds.push_back(open_regular_file(paths[i], sizes[i]));
    if (i + 1 < paths.size() && (sizes[i] == 0 || sizes[i] % page != 0)) return std::nullopt;
    total += sizes[i];
  }
  MappedFile out;
  out.size_ = total;
  if (total == 0) return out;
  // One reserved range, then each file mapped over its part of it.
  const size_t reserved = (total + page - 1) / page * page;
  void* base = ::mmap(nullptr, reserved, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (base == MAP_FAILED) throw InputError(paths.front(), 0, std::string("cannot map: ") + std::strerror(errno));
  out.owner_ = std::shared_ptr<const void>(base, [reserved](const void* p) { ::munmap(const_cast<void*>(p), reserved); });
  size_t offset = 0;
  for (size_t i = 0; i < paths.size() && sizes[i] > 0; ++i) {
    void* mapping = ::mmap(static_cast<char*>(base) + offset, sizes[i], PROT_READ, MAP_PRIVATE | MAP_FIXED, files.fds[i], 0);
    if (mapping == MAP_FAILED) throw InputError(paths[i], 0, std::string("cannot map: ") + std::strerror(errno));
    offset += sizes[i];
  }
  out.data_ = static_cast<const unsigned char*>(base);
  return out;
}

}  // namespace nec
