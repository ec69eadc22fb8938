// `triadcal export CAL.json --format c|yaml|json-matrix -o OUT`: a calibration
// for firmware (C99 code applying it, the gyro too when it has one) or other
// tools (the plain matrix form), see tools/report/calibration_export.h.
#include <yaml-cpp/yaml.h>

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "core/io/calibration_io.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/output_guard.h"
#include "tools/report/calibration_export.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

struct ExportArgs {
  std::string calibration_json, format, out, name;
};

bool IsCIdentifier(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  }
  return true;
}

// JSON -> YAML: maps as blocks, lists of numbers as flow lists, numbers exact.
void EmitYaml(const nlohmann::ordered_json& j, YAML::Emitter* out) {
  if (j.is_object()) {
    *out << YAML::BeginMap;
    for (const auto& [key, value] : j.items()) {
      *out << YAML::Key << key << YAML::Value;
      EmitYaml(value, out);
    }
    *out << YAML::EndMap;
  } else if (j.is_array()) {
    const bool flat = !j.empty() && j[0].is_number();
    *out << (flat ? YAML::Flow : YAML::Block) << YAML::BeginSeq;
    for (const auto& v : j) EmitYaml(v, out);
    *out << YAML::EndSeq;
  } else if (j.is_number()) {
    *out << FormatDouble(j.get<double>());
  } else if (j.is_string()) {
    *out << YAML::DoubleQuoted << j.get<std::string>();
  } else {
    *out << j.dump();
  }
}

int RunExport(const ExportArgs& a, Session& session) {
  if (a.format != "c" && a.format != "yaml" && a.format != "json-matrix") {
    throw InputError("--format: expected c, yaml or json-matrix, got '" + a.format + "'");
  }
  const bool to_stdout = IsStdout(a.out);
  if (to_stdout && a.format == "c") {
    throw InputError("-o -: --format c writes two files (NAME.c and NAME.h), not stdout");
  }
  if (!to_stdout) CheckOutputPath(a.out);
  if (a.format == "c") {
    fs::path c_path(a.out), h_path(a.out);
    c_path.replace_extension(".c");
    h_path.replace_extension(".h");
    CheckOutputPath(c_path.string() == a.out ? h_path.string() : c_path.string());
  }
  const Calibration cal = LoadCalibration(a.calibration_json);
  if (!cal.temperature_terms.empty()) {
    // The exported forms hold one set of parameters.
    throw InputError(a.calibration_json +
                     ": temperature_model: a calibration with a temperature model cannot be "
                     "exported (apply evaluates it; export a fit at one temperature)");
  }
  // Before any output: an effect the exported forms cannot carry.
  if (const std::string why = ExportRefusal(cal); !why.empty()) throw InputError(why);
  session.provenance.RecordInput("calibration", a.calibration_json);
  const std::string provenance = session.provenance.Json().dump();

  if (a.format == "json-matrix") {
    WriteJson(nlohmann::json::parse(MatrixForm(cal).dump()), a.out, session);
  } else if (a.format == "yaml") {
    if (!to_stdout) CheckOverwrite(a.out, session);
    YAML::Emitter y;
    EmitYaml(MatrixForm(cal), &y);
    WriteOutput(a.out,
                "# triadcal calibration, plain matrix form (triadcal export)\n"
                "# provenance: " +
                    provenance + "\n" + y.c_str() + "\n");
  } else {
    const fs::path out(a.out);
    if (out.extension() != ".c" && out.extension() != ".h") {
      throw InputError("-o: for --format c give NAME.c or NAME.h (both are written), got '" +
                       a.out + "'");
    }
    const std::string name = a.name.empty() ? out.stem().string() : a.name;
    if (!IsCIdentifier(name)) {
      throw InputError((a.name.empty() ? "-o: file name '" : "--name: '") + name +
                       "' is not a C identifier (the function is NAME_apply); use --name");
    }
    fs::path c_path = out, h_path = out;
    c_path.replace_extension(".c");
    h_path.replace_extension(".h");
    CheckOverwrite(c_path.string(), session);
    CheckOverwrite(h_path.string(), session);
    // The source includes the header by the name it is written under (the
    // stem of -o), whatever --name calls the function.
    const CExport code = ExportC(cal, name,
                                 "calibration: " + a.calibration_json + " (" + cal.section + ")\n" +
                                     "provenance: " + provenance,
                                 out.stem().string());
    WriteFileAtomically(h_path.string(), code.header);
    WriteFileAtomically(c_path.string(), code.source);
    std::printf("export: %s_apply()%s in %s and %s\n", name.c_str(),
                cal.layout.has_gyro() ? (" and " + name + "_apply_gyro()").c_str() : "",
                h_path.c_str(), c_path.c_str());
    return 0;
  }
  if (to_stdout) return 0;  // stdout holds the export
  std::printf("export: %s (%s) -> %s\n", a.calibration_json.c_str(), cal.section.c_str(),
              a.out.c_str());
  return 0;
}

}  // namespace

Command AddExportCommand(CLI::App& app) {
  auto a = std::make_shared<ExportArgs>();
  Command c;
  c.app = app.add_subcommand(
      "export", "A calibration as C99 code applying it, or as plain matrices (YAML, JSON)");
  c.app
      ->add_option("calibration", a->calibration_json,
                   "OUT of fit, static, diagnose, filter (rts) or compare (batch), or a truth.json")
      ->required();
  c.app->add_option("--format", a->format, "c (NAME.c + NAME.h), yaml or json-matrix")->required();
  c.app
      ->add_option("-o,--output", a->out,
                   "output file (for c: NAME.c or NAME.h; - for stdout with yaml, json-matrix)")
      ->required();
  c.app->add_option("--name", a->name, "C function prefix (default: the file name)");
  c.run = [a](Session& session) { return RunExport(*a, session); };
  return c;
}

}  // namespace triadcal
