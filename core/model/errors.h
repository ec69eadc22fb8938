// Errors that reach the user as one line on stderr: "where: what is wrong".
#pragma once

#include <stdexcept>
#include <string>

namespace triadcal {

// Bad input: a file, a line, a key. The message names the place and the problem.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace triadcal
