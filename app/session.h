// What a job runs in, passed in by its caller instead of process-wide state:
// the provenance its outputs carry (inputs recorded as they are read), whether
// outputs of other inputs may be replaced (--force), the output guard, the
// registry of temporaries, and where progress and warnings go.
// The command line makes one per command (tools/main.cpp); `batch` one per
// run it fits in parallel; Python one per call.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "app/provenance.h"
#include "core/io/file_util.h"
#include "core/io/temporary_files.h"

namespace triadcal {

struct Session {
  Provenance provenance;
  // Replace outputs that hold results of other inputs (app/output_guard.h).
  bool force = false;
  // The files read and the outputs announced (core/io/file_util.h), shared by
  // the copies of the session (and by `batch`'s sessions of its runs): the
  // jobs note what they load into it (RecordInput, NoteInput; core's readers
  // note nothing), and the writes check it (write_options). Null: no guard
  // (a library caller, Python).
  std::shared_ptr<OutputGuard> output_guard;
  // The temporaries being written, removed on a signal: the executable's one
  // registry (tools/main.cpp, core/io/temporary_files.h). Null: a signal
  // leaves a temporary, which the next write of that output removes.
  TemporaryFiles* temporaries = nullptr;
  // Progress of a long job: the stage ("relinearising pass 2") and the
  // fraction of the work done; either may be empty (no progress).
  std::function<void(const std::string&)> stage;
  std::function<void(double)> fraction;
  // A warning for the user (one sentence, e.g. of the loading); may be empty:
  // the jobs also return their warnings (LoadedRun::warnings).
  std::function<void(const std::string&)> warning;

  // An input file loaded: recorded in the provenance (its role and path) and
  // noted in the output guard, so that no output replaces it.
  void RecordInput(const std::string& role, const std::string& path);
  // The same with the file's SHA-256 taken by the caller.
  void RecordInput(const std::string& role, const std::string& path, const std::string& sha256);
  // A file loaded that the provenance does not list (a runs file, a manifest,
  // an OUT a report or a merge reads, the point of `observability --at`):
  // noted in the output guard only. Nothing without a guard.
  void NoteInput(const std::string& path) const;
  // An output announced before the work (OutputGuard::NoteOutput: two
  // outputs never share a file). Nothing without a guard.
  void NoteOutput(const std::string& path) const;
  // What the session's writes are given (core/io/file_util.h): the guard,
  // checked before each write, and the registry of temporaries.
  WriteOptions write_options() const { return {output_guard.get(), temporaries}; }
};

}  // namespace triadcal
