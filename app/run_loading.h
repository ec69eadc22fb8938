// A run as the jobs take it: run.yaml's description and its data, loaded with
// the warnings of the loading (the caller shows them), the inputs recorded in
// the session's provenance.
#pragma once

#include <string>
#include <vector>

#include "app/session.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

struct LoadedRun {
  RunDescription description;
  RunData data;
  // What the loading found worth saying (a mounting that does not fit the
  // data, columns out of range, ...), one sentence each.
  std::vector<std::string> warnings;
};

// Loads run.yaml and its data; records both (and the sensor) in
// session->provenance, notes both in its output guard (Session::RecordInput)
// and says each warning through session->warning (when set). Throws
// InputError for bad input. threads: the job's (0: all cores); with 1 the
// file is parsed and its checksum taken on the calling thread alone.
LoadedRun LoadRun(const std::string& run_yaml, Session* session, int threads = 0);

// The same for a description already read (Python's dict of run.yaml's keys):
// loads its data, records the data file and the sensor.
LoadedRun LoadRun(RunDescription description, Session* session, int threads = 0);

}  // namespace triadcal
