// `triadcal export CAL.json --format c|yaml|json-matrix -o OUT`: a calibration
// for firmware (C99 code applying it, the gyro too when it has one) or other
// tools (the plain matrix form): the export job, app/export_job.h.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "app/export_job.h"
#include "app/output_guard.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "tools/command_util.h"
#include "tools/commands.h"

namespace triadcal {
namespace {

namespace fs = std::filesystem;

struct ExportArgs {
  std::string calibration_json, format, out;
  ExportSettings settings;  // --name, filled by CLI11 directly
};

int RunExport(ExportArgs a, Session& session) {
  ExportSettings& s = a.settings;
  s.format = ParseExportFormat(a.format);
  const bool to_stdout = IsStdout(a.out);
  if (to_stdout && s.format == ExportFormat::kC) {
    throw InputError("-o -: --format c writes two files (NAME.c and NAME.h), not stdout");
  }
  if (!to_stdout) CheckOutputPath(a.out, session);
  // --format c writes both NAME.c and NAME.h, whichever -o names.
  const fs::path out(a.out);
  fs::path c_path = out, h_path = out;
  c_path.replace_extension(".c");
  h_path.replace_extension(".h");
  if (s.format == ExportFormat::kC) {
    CheckOutputPath(c_path.string() == a.out ? h_path.string() : c_path.string(), session);
    if (out.extension() != ".c" && out.extension() != ".h") {
      throw InputError("-o: for --format c give NAME.c or NAME.h (both are written), got '" +
                       a.out + "'");
    }
  }
  const ExportOutcome o = ExportRun(s, a.calibration_json, out.stem().string(), &session);
  switch (s.format) {
    case ExportFormat::kJsonMatrix:
      WriteJson(o.json, a.out, session);
      break;
    case ExportFormat::kYaml:
      if (!to_stdout) CheckOverwrite(a.out, session);
      WriteOutput(a.out, o.yaml, session);
      break;
    case ExportFormat::kC:
      CheckOverwrite(c_path.string(), session);
      CheckOverwrite(h_path.string(), session);
      WriteFileAtomically(h_path.string(), o.c.header, session.write_options());
      WriteFileAtomically(c_path.string(), o.c.source, session.write_options());
      std::printf(
          "export: %s_apply()%s in %s and %s\n", o.name.c_str(),
          o.calibration.layout.has_gyro() ? (" and " + o.name + "_apply_gyro()").c_str() : "",
          h_path.c_str(), c_path.c_str());
      return 0;
  }
  if (to_stdout) return 0;  // stdout holds the export
  std::printf("export: %s (%s) -> %s\n", a.calibration_json.c_str(), o.calibration.section.c_str(),
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
  c.app->add_option("--name", a->settings.name, "C function prefix (default: the file name)");
  c.run = [a](Session& session) { return RunExport(*a, session); };
  return c;
}

}  // namespace triadcal
