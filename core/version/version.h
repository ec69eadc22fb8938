// The version of triadcal and the git commit it was built from, for
// `triadcal --version`, the provenance of every output, the HTML report and
// the Python module's __version__. The version has one source, project() in
// the top CMakeLists.txt; cmake/git_version.cmake writes the definitions into
// the build folder (core/version/version.cpp) at every build, rewriting the
// file only when the commit changes, so a build of the same commit recompiles
// nothing and a new commit recompiles that one file.
#pragma once

namespace triadcal {

// "MAJOR.MINOR.PATCH" of project(triadcal VERSION ...).
const char* ToolVersion();
// The commit of the source tree ("unknown" outside a git checkout; "-dirty"
// appended when it had local changes).
const char* ToolGitCommit();

}  // namespace triadcal
