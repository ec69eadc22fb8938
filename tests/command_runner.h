// Running the built `triadcal` (and other programs) from command-level tests:
// the exit status and what it printed on stderr.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

namespace triadcal {
namespace testing_fixtures {

struct CommandResult {
  int status = -1;  // exit status
  std::string err;  // stderr
};

// Runs `command` through the shell; stdout goes to /dev/null, stderr to
// err_path (read back into the result).
inline CommandResult RunCommand(const std::string& command, const std::string& err_path) {
  CommandResult r;
  const int raw = std::system((command + " > /dev/null 2> '" + err_path + "'").c_str());
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  std::ifstream in(err_path);
  r.err.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  return r;
}

// `triadcal ARGS`.
inline CommandResult RunTriadcal(const std::string& args, const std::string& err_path) {
  return RunCommand(std::string(TRIADCAL_BIN) + " " + args, err_path);
}

}  // namespace testing_fixtures
}  // namespace triadcal
