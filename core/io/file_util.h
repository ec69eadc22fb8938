// Small file helpers shared by every writer: outputs appear whole or not at all.
#pragma once

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace triadcal {

class OutputGuard;     // below
class TemporaryFiles;  // core/io/temporary_files.h

// What a write is given besides its content (each may be null: a library
// caller's plain write).
struct WriteOptions {
  // The command's output guard: the write is refused when the output, or an
  // output announced before it, is one of the inputs noted so far
  // (OutputGuard::CheckOutputsAreNotInputs), so a command with several
  // outputs writes none of them. Null: not checked.
  const OutputGuard* guard = nullptr;
  // The registry the temporary is registered in while it is written, so that
  // the executable's signal handler removes it on SIGINT, SIGTERM or SIGHUP.
  // Null: no removal on a signal.
  TemporaryFiles* temporaries = nullptr;
};

// Writes content to path through a temporary file in the same folder and a
// rename, so that readers never see a partial file. Throws InputError when the
// folder cannot be written, when path is not fit for an output
// (CheckOutputFile), or when options.guard refuses it. A symbolic link to a
// regular file is written through: the file it names is replaced, the link
// stays.
//
// Temporaries: TemporaryPathFor(target), in the target's folder. Removed
// when the write fails, and on a signal when options.temporaries is given
// (the executable's handler); one left by a killed process (kill -9, a power
// cut, a signal without a handler) is removed by the next write of the same
// output on the same host (RemoveStaleTemporaries).
void WriteFileAtomically(const std::string& path, const std::string& content,
                         const WriteOptions& options = {});

// ".tmp.NAME.HOST.PID" beside `path` (NAME its file name, HOST this host's
// name, PID this process).
std::string TemporaryPathFor(const std::string& path);
// Removes the temporaries of `path` that processes of this host no longer
// running left behind (only names of the form above, and the ".tmp.NAME.PID"
// of earlier versions; a temporary of a running process, or of another host,
// stays).
void RemoveStaleTemporaries(const std::string& path);
// The same for any staging entry "PREFIX.HOST.PID" (or "PREFIX.PID") in
// `folder` ("" is the working folder): regular files, or with `directories`
// folders (removed with their content), of processes of this host that are gone.
void RemoveStaleEntries(const std::string& folder, const std::string& prefix, bool directories);
// This host's name as it appears in temporaries (letters, digits, - and _).
std::string HostTag();
// True when `pid` names no running process of this host.
bool ProcessIsGone(long pid);

// Outputs are regular files. Throws InputError("PATH: cannot write: WHY")
// when `path` is empty, exists and is not a regular file (a directory, a FIFO,
// a device node, a socket), is a symbolic link to anything but a regular file
// (or to nothing), or cannot be looked up (a symlink loop, a name too long, a
// folder on the way not searchable). A missing file is fine.
void CheckOutputFile(const std::string& path);

// Why `path` cannot be read as an input file: "" when it is a readable
// regular file (through symbolic links); otherwise "no such file", "is a
// directory, not a file", "is a FIFO (named pipe), not a regular file", "is a
// device node, not a regular file", "too many levels of symbolic links (a
// loop?)", "file name too long", "permission denied", ...
std::string InputFileProblem(const std::string& path);
// Throws InputError("PATH: cannot read (no such file or not readable)") for a
// missing file and InputError("PATH: cannot read: WHY") for the other
// problems above; the path is quoted as an Excerpt when it is very long.
void CheckInputFile(const std::string& path);
// A path for a message: itself, or an excerpt when longer than 240 characters
// (a name longer than the system allows).
std::string PathForMessage(const std::string& path);

// At most max_bytes of a regular file from byte `offset` ("" when it is not a
// regular file or cannot be read): the output guard reads no more of an
// existing output than this.
std::string ReadFileRange(const std::string& path, std::uintmax_t offset, std::size_t max_bytes);

// The output guard of a command: the files it read and the outputs it
// announced, so that an output never replaces an input and two outputs never
// share a file. A value that core makes none of and keeps nowhere: the
// command's session holds one (app/session.h), the jobs note the files they
// load into it (core's readers note nothing), and the writers are given it
// (WriteOptions::guard). Thread-safe: `batch` loads its runs on several
// threads into the command's guard.
class OutputGuard {
 public:
  void NoteInput(const std::string& path);
  // Throws InputError("PATH: given for two outputs ...") when another output
  // names the same file.
  void NoteOutput(const std::string& path);
  // Throws InputError("PATH: is the input file 'IN' ...") when an output noted
  // so far, or `path`, is one of the inputs noted so far.
  void CheckOutputsAreNotInputs(const std::string& path) const;

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> inputs_, outputs_;
};

// Reads a whole file; throws InputError("PATH: cannot read ...")
// (CheckInputFile first: a FIFO or a device is never opened).
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
