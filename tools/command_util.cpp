#include "tools/command_util.h"

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <unistd.h>

#include "core/model/errors.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/io/run_io.h"
#include "core/io/run_description_io.h"
#include "solvers/static/mounting_search.h"

namespace triadcal {

LoadedRun LoadRunOrThrow(const std::string& run_yaml) {
  LoadedRun r;
  r.description = LoadRunDescription(run_yaml);
  SetReadingsUnitName(ReadingsUnit(r.description));  // output units named for what was read
  RunWarnings warnings;
  r.data = LoadRunData(r.description, &warnings);
  const std::string mounting = MountingWarning(r.description, r.data);
  if (!mounting.empty()) warnings.lines.push_back(mounting);
  for (const std::string& w : warnings.lines) std::cerr << "triadcal: warning: " << OneLine(w) << "\n";
  return r;
}

std::vector<std::string> SplitList(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

std::vector<Effect> ParseEffectList(const std::string& list, const std::string& option) {
  std::vector<Effect> out;
  for (const std::string& item : SplitList(list)) {
    try {
      out.push_back(EffectFromName(item));
    } catch (const std::invalid_argument& e) {
      throw InputError(option + ": " + e.what());
    }
  }
  return out;
}

namespace {
bool& ProgressShown() {
  static bool shown = false;
  return shown;
}
}  // namespace

void ShowProgress(const std::string& what, double fraction) {
  if (!isatty(fileno(stderr))) return;
  std::fprintf(stderr, "\r%s %3.0f%%", what.c_str(), 100.0 * fraction);
  std::fflush(stderr);
  ProgressShown() = true;
}

void EndProgress() {
  if (ProgressShown()) {
    std::fprintf(stderr, "\r%60s\r", "");
    ProgressShown() = false;
  }
}

void CheckOutputPath(const std::string& path) {
  namespace fs = std::filesystem;
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (!fs::is_directory(dir) || access(dir.c_str(), W_OK) != 0) {
    throw InputError(path + ": cannot write (folder missing or not writable)");
  }
  NoteOutputFile(path);
}

void WriteJson(const nlohmann::json& j, const std::string& path) {
  WriteFileAtomically(path, j.dump(2) + "\n");
}

}  // namespace triadcal
