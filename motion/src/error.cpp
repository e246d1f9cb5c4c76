// InputError message formatting.
#include "nec/motion/error.h"

namespace nec {

namespace {
std::string format_input_error(const std::string& file, long line, const std::string& problem) {
  if (line > 0) return file + ":" + std::to_string(line) + ": " + problem;
  return file + ": " + problem;
}
}  // namespace

InputError::InputError(const std::string& file, long line, const std::string& problem)
    : std::runtime_error(format_input_error(file, line, problem)) {}

}  // namespace nec
