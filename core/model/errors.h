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

// The text of an error as one printable line: control characters (a newline,
// a tab, an escape byte read from a file) become \n, \t or \xNN.
std::string OneLine(const std::string& text);

}  // namespace triadcal
