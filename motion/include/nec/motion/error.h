// InputError: what every reader throws for bad user input. The message names
// the file, the line (when known) and the problem, ready to print as is:
//   dog.bvh:12: unknown channel 'Wrotation'
// Commands catch it, print it and exit with code 1.
#pragma once

#include <stdexcept>
#include <string>

namespace nec {

class InputError : public std::runtime_error {
 public:
  // line <= 0 means "no line": "file: problem".
  InputError(const std::string& file, long line, const std::string& problem);
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace nec
