#include "core/io/runs_file_io.h"

#include <filesystem>
#include <set>

#include "core/io/yaml_fields.h"
#include "core/model/errors.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

std::string DefaultName(const std::string& run_yaml) {
  const fs::path p(run_yaml);
  const std::string stem = p.stem().string();
  if (stem == "run") {
    const std::string folder = fs::absolute(p).parent_path().filename().string();
    if (!folder.empty()) return folder;
  }
  return stem;
}

std::string Canonical(const std::string& path) {
  std::error_code ec;
  const fs::path c = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? path : c.string();
}

// Two entries of one file or one name: an error naming both.
void CheckDistinct(const RunsFile& f) {
  for (std::size_t r = 0; r < f.runs.size(); ++r) {
    for (std::size_t q = 0; q < r; ++q) {
      if (Canonical(f.runs[r].run_yaml) == Canonical(f.runs[q].run_yaml)) {
        throw InputError(f.runs[r].where + ": " + f.runs[r].run_yaml + " is listed twice (also " +
                         f.runs[q].where + ")");
      }
      if (f.runs[r].name == f.runs[q].name) {
        throw InputError(f.runs[r].where + ": the name '" + f.runs[r].name + "' is also that of " +
                         f.runs[q].where + " (give each run a name)");
      }
    }
  }
}

std::vector<std::string> ReadNames(const YAML::Node& node, const YamlPlace& at) {
  if (!node.IsSequence()) at.Fail("expected a list of parameter names, got " + DescribeNode(node));
  std::vector<std::string> out;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string name = ReadString(node[i], at.Index(i));
    if (!seen.insert(name).second) at.Index(i).Fail("'" + name + "' is listed twice");
    out.push_back(name);
  }
  return out;
}

}  // namespace

bool IsRunsFile(const std::string& yaml_path) {
  try {
    const YAML::Node root = LoadYamlFile(yaml_path);
    return root.IsMap() && root["runs"];
  } catch (const std::exception&) {
    return false;  // the run reader gives the error
  }
}

RunsFile LoadRunsFile(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  const YamlPlace at{path, ""};
  CheckKeys(root, at, {"runs", "per_run", "shared", "temperature"});
  RunsFile f;
  f.path = path;
  const YAML::Node& runs = root["runs"];
  const YamlPlace rat = at.Child("runs");
  if (!runs || !runs.IsSequence() || runs.size() == 0) {
    rat.Fail("expected a list of runs ({run: FILE.yaml, name: NAME, temperature_C: T})");
  }
  const fs::path folder = fs::path(path).parent_path();
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const YamlPlace p = rat.Index(i);
    RunsFile::Entry e;
    e.where = p.where + ": " + p.path.substr(p.path.front() == '.' ? 1 : 0);
    const YAML::Node& n = runs[i];
    if (n.IsScalar()) {
      e.run_yaml = (folder / ReadString(n, p)).string();
    } else {
      CheckKeys(n, p, {"run", "name", "temperature_C"});
      if (!n["run"]) p.Child("run").Fail("missing: the run description (run.yaml)");
      e.run_yaml = (folder / ReadString(n["run"], p.Child("run"))).string();
      if (n["name"]) {
        e.name = ReadString(n["name"], p.Child("name"));
        if (e.name.empty() || e.name.find_first_of("@ ,") != std::string::npos) {
          p.Child("name").Fail("expected a name without '@', ',' or spaces");
        }
      }
      if (n["temperature_C"]) {
        const double t = ReadNumber(n["temperature_C"], p.Child("temperature_C"));
        if (!(t >= -100.0 && t <= 200.0)) {
          p.Child("temperature_C").Fail("expected a temperature of -100 to 200 degC");
        }
        e.temperature_C = t;
      }
    }
    if (e.name.empty()) e.name = DefaultName(e.run_yaml);
    f.runs.push_back(e);
  }
  if (root["per_run"]) f.per_run = ReadNames(root["per_run"], at.Child("per_run"));
  if (root["shared"]) f.shared = ReadNames(root["shared"], at.Child("shared"));
  if (root["temperature"]) {
    const YamlPlace t = at.Child("temperature");
    const YAML::Node& n = root["temperature"];
    CheckKeys(n, t, {"reference_C", "degree"});
    if (n["reference_C"]) f.temperature_ref_C = ReadNumber(n["reference_C"], t.Child("reference_C"));
    if (!n["degree"] || !n["degree"].IsMap()) {
      t.Child("degree").Fail("expected a map {parameter: polynomial degree}");
    }
    for (const auto& kv : n["degree"]) {
      const std::string name = KeyOf(kv.first, t.Child("degree"));
      const double d = ReadNumber(kv.second, t.Child("degree").Child(name));
      if (d != 1.0 && d != 2.0 && d != 3.0) {
        t.Child("degree").Child(name).Fail("expected a polynomial degree of 1, 2 or 3");
      }
      f.temperature_degree[name] = static_cast<int>(d);
    }
  }
  CheckDistinct(f);
  return f;
}

RunsFile RunsFromCommandLine(const std::vector<std::string>& run_yamls) {
  RunsFile f;
  for (std::size_t i = 0; i < run_yamls.size(); ++i) {
    RunsFile::Entry e;
    e.run_yaml = run_yamls[i];
    e.name = DefaultName(run_yamls[i]);
    e.where = "command line: run " + std::to_string(i + 1) + " (" + run_yamls[i] + ")";
    f.runs.push_back(e);
  }
  CheckDistinct(f);
  return f;
}

}  // namespace triadcal
