// Small file helpers shared by every writer: outputs appear whole or not at all.
#pragma once

#include <string>

namespace triadcal {

// Writes content to path through a temporary file in the same folder and a
// rename, so that readers never see a partial file. Throws InputError when the
// folder cannot be written.
void WriteFileAtomically(const std::string& path, const std::string& content);

// The output guard of the command line (off by default, so that tests may
// rewrite what they read): once on, every file read is noted as an input and
// every output is checked before anything is written, so an output never
// replaces an input and two outputs never share a file.
// Thread-safe: readers note their files from several threads (`batch`).
void EnableOutputGuard();
// Switches the guard off and forgets what it noted (tests).
void DisableOutputGuard();
// Notes a file read (readers call it; a no-op while the guard is off).
void NoteInputFile(const std::string& path);
// Notes an output before the work starts; throws InputError("PATH: given for
// two outputs") when another output names the same file.
void NoteOutputFile(const std::string& path);
// Throws InputError("PATH: is the input file 'IN' ...") when an output noted so
// far, or `path`, is one of the inputs noted so far. WriteFileAtomically calls
// it before writing, so a command with several outputs writes none of them.
void CheckOutputsAreNotInputs(const std::string& path);

// Reads a whole file; throws InputError("PATH: cannot read ...").
std::string ReadFile(const std::string& path);

// Shortest decimal text that reads back to exactly the same double.
std::string FormatDouble(double x);

// Resolves a data path written in a run or scenario file: relative paths are
// relative to the folder of that file. A path starting with "shared:" names a
// file of the project's shared data folder, found as TRIADCAL_SHARED or as a
// folder "shared" beside any parent of the referring file's folder; empty
// string when no such folder exists.
std::string ResolveDataPath(const std::string& referring_file, const std::string& path);

}  // namespace triadcal
