#include "app/manifest.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

#include "core/io/file_util.h"
#include "core/io/yaml_fields.h"
#include "core/model/effects.h"
#include "core/model/errors.h"
#include "core/model/parameters.h"

namespace triadcal {
namespace {

// Every parameter name a limit may use: the base ones and every effect's.
bool KnownParameter(const std::string& name) {
  static const ParameterLayout every = [] {
    std::vector<Effect> all;
    for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
    return ParameterLayout(all);
  }();
  return every.IndexOf(name) >= 0;
}

// "" when `serial` can name a folder, else what is wrong with it.
std::string SerialProblem(const std::string& serial) {
  const bool ok =
      !serial.empty() && serial[0] != '.' && std::all_of(serial.begin(), serial.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
      });
  if (ok) return "";
  return "'" + serial +
         "' cannot name a folder (letters, digits, '.', '_', '-'; not starting with '.')";
}

std::string Trim(const std::string& s) {
  const std::size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const std::size_t e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) cells.push_back(Trim(cell));
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

bool ParseBool(const std::string& text, bool* out) {
  if (text == "true" || text == "yes" || text == "1") return *out = true, true;
  if (text == "false" || text == "no" || text == "0" || text.empty()) return *out = false, true;
  return false;
}

ParameterLimit& LimitFor(std::vector<ParameterLimit>* limits, const std::string& name) {
  for (ParameterLimit& l : *limits) {
    if (l.parameter == name) return l;
  }
  limits->push_back(ParameterLimit{name, {}, {}, {}});
  return limits->back();
}

void CheckLimit(const ParameterLimit& l, const std::string& where) {
  if (l.min && l.max && *l.min > *l.max) {
    throw InputError(where + ": " + l.parameter + ": min " + FormatDouble(*l.min) +
                     " is above max " + FormatDouble(*l.max));
  }
  if (l.sigma_max && !(*l.sigma_max > 0)) {
    throw InputError(where + ": " + l.parameter + ": sigma_max must be > 0");
  }
}

// ---- CSV

std::vector<ManifestEntry> LoadCsvManifest(const std::string& path) {
  std::stringstream in(ReadFile(path));
  std::string line;
  int line_no = 0;
  std::vector<std::string> header;
  int header_line = 0;
  // Column -> (parameter, field) for the limit columns.
  struct LimitColumn {
    std::string parameter, field;
  };
  std::map<int, LimitColumn> limit_columns;
  int col_serial = -1, col_run = -1, col_diagnose = -1;
  std::vector<ManifestEntry> out;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = Trim(line);
    if (t.empty() || t[0] == '#') continue;
    const std::vector<std::string> cells = SplitCells(t);
    const std::string at = path + ":" + std::to_string(line_no);
    if (header.empty()) {
      header = cells;
      header_line = line_no;
      for (int c = 0; c < static_cast<int>(cells.size()); ++c) {
        const std::string& h = cells[c];
        if (h == "serial") {
          col_serial = c;
        } else if (h == "run") {
          col_run = c;
        } else if (h == "diagnose") {
          col_diagnose = c;
        } else {
          std::string field;
          for (const char* f : {"_sigma_max", "_min", "_max"}) {
            const std::string suffix = f;
            if (h.size() > suffix.size() &&
                h.compare(h.size() - suffix.size(), suffix.size(), suffix) == 0) {
              field = suffix.substr(1);
              break;
            }
          }
          const std::string name = h.substr(0, h.size() - field.size() - 1);
          if (field.empty() || !KnownParameter(name)) {
            throw InputError(at + ": " + h +
                             ": unknown column (serial, run, diagnose, or PARAM_min, PARAM_max, "
                             "PARAM_sigma_max with PARAM a parameter name of SPEC section 3)");
          }
          limit_columns[c] = LimitColumn{name, field};
        }
      }
      if (col_serial < 0) throw InputError(at + ": serial: missing column");
      if (col_run < 0) throw InputError(at + ": run: missing column");
      continue;
    }
    if (cells.size() != header.size()) {
      throw InputError(at + ": expected " + std::to_string(header.size()) +
                       " cells as the header on line " + std::to_string(header_line) + ", got " +
                       std::to_string(cells.size()));
    }
    ManifestEntry e;
    e.serial = cells[col_serial];
    if (!SerialProblem(e.serial).empty()) {
      throw InputError(at + ": serial: " + SerialProblem(e.serial));
    }
    e.run = cells[col_run];
    if (e.run.empty()) throw InputError(at + ": run: empty");
    e.run_path = ResolveDataPath(path, e.run);
    if (e.run_path.empty()) e.run_path = e.run;
    if (col_diagnose >= 0 && !ParseBool(cells[col_diagnose], &e.diagnose)) {
      throw InputError(at + ": diagnose: expected true or false, got '" + cells[col_diagnose] +
                       "'");
    }
    for (const auto& [c, lc] : limit_columns) {
      if (cells[c].empty()) continue;
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(cells[c].c_str(), &end);
      if (end == cells[c].c_str() || *end != '\0' || errno || !std::isfinite(v)) {
        throw InputError(at + ": " + header[c] + ": expected a number, got '" + cells[c] + "'");
      }
      ParameterLimit& l = LimitFor(&e.limits, lc.parameter);
      (lc.field == "min" ? l.min : lc.field == "max" ? l.max : l.sigma_max) = v;
    }
    for (const ParameterLimit& l : e.limits) CheckLimit(l, at);
    out.push_back(std::move(e));
  }
  if (header.empty()) throw InputError(path + ": empty manifest (expected a header line)");
  return out;
}

// ---- YAML

std::vector<ParameterLimit> ReadLimits(const YAML::Node& node, const YamlPlace& at) {
  std::vector<ParameterLimit> limits;
  if (!node.IsMap()) at.Fail("expected a map of parameter: {min, max, sigma_max}");
  std::vector<std::string> names;
  for (const auto& kv : node) names.push_back(kv.first.as<std::string>());
  for (const std::string& name : names) {
    const YamlPlace p = at.Child(name);
    if (!KnownParameter(name)) p.Fail("unknown parameter (names of SPEC section 3)");
    CheckKeys(node[name], p, {"min", "max", "sigma_max"});
    ParameterLimit l{name, {}, {}, {}};
    if (node[name]["min"]) l.min = ReadNumber(node[name]["min"], p.Child("min"));
    if (node[name]["max"]) l.max = ReadNumber(node[name]["max"], p.Child("max"));
    if (node[name]["sigma_max"]) {
      l.sigma_max = ReadPositive(node[name]["sigma_max"], p.Child("sigma_max"));
    }
    if (l.min && l.max && *l.min > *l.max) {
      p.Fail("min " + FormatDouble(*l.min) + " is above max " + FormatDouble(*l.max));
    }
    limits.push_back(l);
  }
  return limits;
}

bool ReadBool(const YAML::Node& node, const YamlPlace& at) {
  bool b = false;
  if (!node.IsScalar() || !ParseBool(node.Scalar(), &b)) {
    at.Fail("expected true or false, got " + DescribeNode(node));
  }
  return b;
}

std::vector<ManifestEntry> LoadYamlManifest(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  const YamlPlace top{path, ""};
  CheckKeys(root, top, {"limits", "diagnose", "runs"});
  std::vector<ParameterLimit> defaults;
  if (root["limits"]) defaults = ReadLimits(root["limits"], top.Child("limits"));
  bool diagnose = false;
  if (root["diagnose"]) diagnose = ReadBool(root["diagnose"], top.Child("diagnose"));
  const YamlPlace runs_at = top.Child("runs");
  if (!root["runs"] || !root["runs"].IsSequence()) runs_at.Fail("expected a list of runs");
  std::vector<ManifestEntry> out;
  for (std::size_t i = 0; i < root["runs"].size(); ++i) {
    const YAML::Node r = root["runs"][i];
    const YamlPlace at = runs_at.Index(i);
    CheckKeys(r, at, {"serial", "run", "diagnose", "limits"});
    ManifestEntry e;
    if (!r["serial"]) at.Child("serial").Fail("missing");
    if (!r["run"]) at.Child("run").Fail("missing");
    e.serial = ReadString(r["serial"], at.Child("serial"));
    if (!SerialProblem(e.serial).empty()) at.Child("serial").Fail(SerialProblem(e.serial));
    e.run = ReadString(r["run"], at.Child("run"));
    e.run_path = ResolveDataPath(path, e.run);
    if (e.run_path.empty()) e.run_path = e.run;
    e.diagnose = r["diagnose"] ? ReadBool(r["diagnose"], at.Child("diagnose")) : diagnose;
    e.limits = defaults;
    if (r["limits"]) {
      for (const ParameterLimit& l : ReadLimits(r["limits"], at.Child("limits"))) {
        LimitFor(&e.limits, l.parameter) = l;
      }
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

std::vector<ManifestEntry> LoadManifest(const std::string& path) {
  auto ends_with = [&](const std::string& s) {
    return path.size() >= s.size() && path.compare(path.size() - s.size(), s.size(), s) == 0;
  };
  if (ends_with(".csv")) return LoadCsvManifest(path);
  if (ends_with(".yaml") || ends_with(".yml")) return LoadYamlManifest(path);
  throw InputError(path + ": manifest: expected a .csv or .yaml file");
}

}  // namespace triadcal
