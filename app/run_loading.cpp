#include "app/run_loading.h"

#include <future>
#include <utility>

#include "core/io/file_util.h"
#include "core/io/run_description_io.h"
#include "core/io/run_io.h"
#include "core/io/sha256.h"
#include "solvers/static/mounting_search.h"

namespace triadcal {

LoadedRun LoadRun(const std::string& run_yaml, Session* session, int threads) {
  RunDescription description = LoadRunDescription(run_yaml);
  session->RecordInput("run", run_yaml);
  return LoadRun(std::move(description), session, threads);
}

LoadedRun LoadRun(RunDescription description, Session* session, int threads) {
  LoadedRun r;
  r.description = std::move(description);
  session->provenance.RecordSensor(r.description.sensor_serial, r.description.sensor_model);
  // The data file's checksum (provenance) is taken on a second thread while
  // the file is parsed: both read it from the page cache. Not a path that is
  // no readable file (a FIFO would block the thread; LoadRunData says what
  // it is), nor with one thread.
  const std::string& path = r.description.data_path;
  std::future<std::string> checksum = std::async(
      InputFileProblem(path).empty() && threads != 1 ? std::launch::async : std::launch::deferred,
      [path] { return Sha256OfFile(path); });
  RunWarnings warnings;
  r.data = LoadRunData(r.description, &warnings, threads);
  r.warnings = std::move(warnings.lines);
  const std::string mounting = MountingWarning(r.description, r.data);
  if (!mounting.empty()) r.warnings.push_back(mounting);
  if (session->warning) {
    for (const std::string& w : r.warnings) session->warning(w);
  }
  session->RecordInput("data", path, checksum.get());
  return r;
}

}  // namespace triadcal
