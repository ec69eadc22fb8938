// Errors that reach the user as one line on stderr: "where: what is wrong".
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace triadcal {

// Bad input: a file, a line, a key. The message names the place and the problem.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

// A bad setting found below the command layer. Solvers name the setting by
// the field of their options struct ("static_positions"), never by a
// command-line flag; the command that read it from a flag rethrows it naming
// the flag (tools/command_util.h WithFlags): "--static-positions: expected ...".
class OptionError : public InputError {
 public:
  OptionError(const std::string& option, const std::string& problem)
      : InputError(option + ": " + problem), option_(option), problem_(problem) {}
  const std::string& option() const { return option_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string option_, problem_;
};
// The text of an error as one printable line: control characters (a newline,
// a tab, an escape byte read from a file) become \n, \t or \xNN.
std::string OneLine(const std::string& text);

// At most `max_chars` characters of text read from an input, escaped as by
// OneLine, for quoting it in an error: a longer text keeps its first
// max_chars - 20 and last 12 characters around "...". An error never echoes
// more of a file than this (a field, a header name, a JSON value).
std::string Excerpt(const std::string& text, std::size_t max_chars = 60);

}  // namespace triadcal
