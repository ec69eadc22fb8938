// What a job runs in, passed in by its caller instead of process-wide state:
// the provenance its outputs carry (inputs recorded as they are read), whether
// outputs of other inputs may be replaced (--force), the output guard, and
// where progress and warnings go.
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
  // the copies of the session; the command installs it on its threads
  // (ScopedOutputGuard). Null: no guard (a library caller).
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

  // What the session's writes are given (core/io/file_util.h).
  WriteOptions write_options() const {
    WriteOptions o;
    o.temporaries = temporaries;
    return o;
  }
};

}  // namespace triadcal
