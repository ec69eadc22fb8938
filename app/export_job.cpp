#include "app/export_job.h"

#include <yaml-cpp/yaml.h>

#include <cctype>

#include "core/io/file_util.h"
#include "core/model/errors.h"

namespace triadcal {
namespace {

bool IsCIdentifier(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  }
  return true;
}

std::string NotAnIdentifier(const std::string& where, const std::string& name) {
  return where + name + "' is not a C identifier (the function is NAME_apply); use --name";
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

}  // namespace

const char* ExportFormatName(ExportFormat format) {
  switch (format) {
    case ExportFormat::kC:
      return "c";
    case ExportFormat::kYaml:
      return "yaml";
    case ExportFormat::kJsonMatrix:
      break;
  }
  return "json-matrix";
}

ExportFormat ParseExportFormat(const std::string& text) {
  for (ExportFormat f : {ExportFormat::kC, ExportFormat::kYaml, ExportFormat::kJsonMatrix}) {
    if (text == ExportFormatName(f)) return f;
  }
  throw InputError("--format: expected c, yaml or json-matrix, got '" + text + "'");
}

void ExportSettings::Validate() const {
  if (!name.empty() && !IsCIdentifier(name)) throw InputError(NotAnIdentifier("--name: '", name));
}

ExportOutcome ExportRun(const ExportSettings& s, const std::string& calibration_json,
                        const std::string& file_base, Session* session) {
  s.Validate();
  ExportOutcome o;
  o.calibration = LoadCalibration(calibration_json);
  const Calibration& cal = o.calibration;
  if (!cal.temperature_terms.empty()) {
    // The exported forms hold one set of parameters.
    throw InputError(calibration_json +
                     ": temperature_model: a calibration with a temperature model cannot be "
                     "exported (apply evaluates it; export a fit at one temperature)");
  }
  // Before any output: an effect the exported forms cannot carry.
  if (const std::string why = ExportRefusal(cal); !why.empty()) throw InputError(why);
  session->RecordInput("calibration", calibration_json);
  const std::string provenance = session->provenance.Json().dump();
  switch (s.format) {
    case ExportFormat::kJsonMatrix:
      o.json = nlohmann::json::parse(MatrixForm(cal).dump());
      break;
    case ExportFormat::kYaml: {
      YAML::Emitter y;
      EmitYaml(MatrixForm(cal), &y);
      o.yaml = "# triadcal calibration, plain matrix form (triadcal export)\n# provenance: " +
               provenance + "\n" + y.c_str() + "\n";
      break;
    }
    case ExportFormat::kC:
      o.name = s.name.empty() ? file_base : s.name;
      if (!IsCIdentifier(o.name)) throw InputError(NotAnIdentifier("-o: file name '", o.name));
      // The source includes the header by the name it is written under,
      // whatever --name calls the function.
      o.c = ExportC(cal, o.name,
                    "calibration: " + calibration_json + " (" + cal.section + ")\n" +
                        "provenance: " + provenance,
                    file_base);
      break;
  }
  return o;
}

}  // namespace triadcal
