// `triadcal export CAL.json --format c|yaml|json-matrix`: a calibration in
// the forms other programs use (app/calibration_export.h): C99 code applying
// it, or the plain matrix form as YAML or JSON. The settings and the job,
// which gives the files' contents; the command writes them.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/calibration_export.h"
#include "app/session.h"
#include "core/io/calibration_io.h"

namespace triadcal {

enum class ExportFormat { kC, kYaml, kJsonMatrix };

// "c", "yaml", "json-matrix", and back; throws InputError("--format:
// expected c, yaml or json-matrix, got 'X'").
const char* ExportFormatName(ExportFormat format);
ExportFormat ParseExportFormat(const std::string& text);

// The settings of `export` (--format has no default: the command asks for it).
struct ExportSettings {
  ExportFormat format = ExportFormat::kJsonMatrix;
  std::string name;  // C function prefix; empty: the base of the file names

  // Throws InputError naming the option (as the command line's flag).
  void Validate() const;
};

struct ExportOutcome {
  Calibration calibration;
  nlohmann::json json;  // json-matrix: the matrix form (the writer adds the provenance)
  std::string yaml;     // yaml: the whole text, provenance in its heading
  CExport c;            // c: header and source, provenance in their heading
  std::string name;     // c: the function prefix (NAME_apply)
};

// Loads the calibration (recorded in the session's provenance) and gives the
// export of s.format. A calibration with a temperature model, or an effect
// the exported forms do not carry, is refused (InputError, before any
// output). For c, file_base is the base of the file names (FILE.h, FILE.c),
// also the function prefix when s.name is empty ("-o: file name 'X' is not a
// C identifier ..." when it is none).
ExportOutcome ExportRun(const ExportSettings& s, const std::string& calibration_json,
                        const std::string& file_base, Session* session);

}  // namespace triadcal
