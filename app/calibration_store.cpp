#include "app/calibration_store.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>
#include <utility>

#include "core/model/errors.h"

namespace triadcal {
namespace fs = std::filesystem;
namespace {

std::string FormatUtc(const char* format) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

bool IsDate(const std::string& s) {
  int y = 0, m = 0, d = 0, used = 0;
  return s.size() == 10 && std::sscanf(s.c_str(), "%4d-%2d-%2d%n", &y, &m, &d, &used) == 3 &&
         used == 10 && s[4] == '-' && s[7] == '-' && m >= 1 && m <= 12 && d >= 1 && d <= 31;
}

// "2026-11-23" -> (date, 1), "2026-11-23_3" -> (date, 3); k = 0: not a calibration folder.
std::pair<std::string, int> ParseFolder(const std::string& name) {
  const std::string date = name.substr(0, 10);
  if (!IsDate(date)) return {"", 0};
  if (name.size() == 10) return {date, 1};
  int k = 0, used = 0;
  if (name[10] != '_' || std::sscanf(name.c_str() + 11, "%d%n", &k, &used) != 1 ||
      11 + used != static_cast<int>(name.size()) || k < 2) {
    return {"", 0};
  }
  return {date, k};
}

std::string FolderName(const std::string& date, int k) {
  return k == 1 ? date : date + "_" + std::to_string(k);
}

}  // namespace

std::string UtcDateToday() { return FormatUtc("%Y-%m-%d"); }
std::string UtcStampNow() { return FormatUtc("%Y%m%dT%H%M%SZ"); }

void CheckDate(const std::string& date) {
  if (!IsDate(date)) throw InputError("--date: expected YYYY-MM-DD, got '" + date + "'");
}

std::string ClaimCalibrationFolder(const std::string& dir, const std::string& serial,
                                   const std::string& date) {
  const fs::path unit = fs::path(dir) / serial;
  std::error_code ec;
  fs::create_directories(unit, ec);
  if (ec) throw InputError(unit.string() + ": cannot create folder (" + ec.message() + ")");
  for (int k = 1;; ++k) {
    const std::string name = FolderName(date, k);
    if (fs::create_directory(unit / name, ec)) return serial + "/" + name;
    if (ec)
      throw InputError((unit / name).string() + ": cannot create folder (" + ec.message() + ")");
  }
}

std::string PreviousCalibration(const std::string& dir, const std::string& serial,
                                const std::string& folder) {
  const auto mine = ParseFolder(fs::path(folder).filename().string());
  std::pair<std::string, int> best{"", 0};
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(fs::path(dir) / serial, ec)) {
    const auto f = ParseFolder(e.path().filename().string());
    if (f.second == 0 || !(f < mine) || !(best < f)) continue;
    std::ifstream in(e.path() / "calibration.json");
    if (!in) continue;
    std::stringstream ss;
    ss << in.rdbuf();
    const nlohmann::json j = nlohmann::json::parse(ss.str(), nullptr, false);
    if (j.is_discarded() || !j.value("converged", false)) continue;
    best = f;
  }
  return best.second ? serial + "/" + FolderName(best.first, best.second) : "";
}

nlohmann::json ChangeInSigma(const nlohmann::json& now, const nlohmann::json& before) {
  nlohmann::json out = nlohmann::json::object();
  for (auto it = now.begin(); it != now.end(); ++it) {
    if (!before.contains(it.key())) continue;
    const nlohmann::json& a = it.value();
    const nlohmann::json& b = before[it.key()];
    if (!a.value("estimable", true) || !b.value("estimable", true)) continue;
    if (!a.contains("sigma") || !a["sigma"].is_number() || !b.contains("sigma") ||
        !b["sigma"].is_number()) {
      continue;  // held: no estimate to compare
    }
    const double s = std::hypot(a["sigma"].get<double>(), b["sigma"].get<double>());
    if (!(s > 0)) continue;
    out[it.key()] = (a.value("value", 0.0) - b.value("value", 0.0)) / s;
  }
  return out;
}

}  // namespace triadcal
