// Whole-file reading and atomic writing (temp file + rename, so a failed
// write never leaves a half-written output behind).
#pragma once

#include <string>
#include <string_view>

namespace nec {

// Throws InputError naming the file when it cannot be read or exceeds max_bytes.
std::string read_file(const std::string& path, size_t max_bytes = size_t{1} << 32);
// Writes `contents` to `path` through a temporary file in the same directory.
// Throws std::runtime_error naming the file on failure.
void write_file_atomic(const std::string& path, std::string_view contents);

}  // namespace nec
