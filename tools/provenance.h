// The `triadcal` binary's own part of the provenance (app/provenance.h): its
// version and the git commit it was built from, defined in the file that
// cmake/git_version.cmake generates at every build.
#pragma once

namespace triadcal {

// The tool version and the git commit the binary was built from ("unknown"
// outside a git checkout; "-dirty" appended when it had local changes).
const char* ToolVersion();
const char* ToolGitCommit();

}  // namespace triadcal
