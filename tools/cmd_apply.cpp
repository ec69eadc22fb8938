// `triadcal apply CALIBRATION.json RUN.yaml -o corrected.csv`: the apply job
// (app/apply_job.h), its CSV written, its warnings and a line printed.
#include <cstdio>
#include <memory>
#include <string>

#include "app/apply_job.h"
#include "app/output_guard.h"
#include "tools/command_util.h"
#include "tools/commands.h"

namespace triadcal {
namespace {

struct ApplyArgs {
  std::string calibration_json, run_yaml, out_csv;
};

int RunApply(const ApplyArgs& a, Session& session) {
  const bool to_stdout = IsStdout(a.out_csv);
  if (!to_stdout) CheckOutputPath(a.out_csv, session);
  const ApplyOutcome o = ApplyRun(a.calibration_json, a.run_yaml, &session);
  if (!to_stdout) CheckOverwrite(a.out_csv, session);
  for (const std::string& w : o.warnings) {
    std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(w).c_str());
  }
  WriteOutput(a.out_csv, o.csv, session);
  if (to_stdout) return 0;  // stdout holds the CSV
  std::printf("apply: %zu samples, %d parameters from %s (%s)%s\nwrote %s\n", o.samples,
              o.calibration.layout.size(), a.calibration_json.c_str(),
              o.calibration.section.c_str(), o.gyro ? "; accelerometer and gyro" : "",
              a.out_csv.c_str());
  return 0;
}

}  // namespace

Command AddApplyCommand(CLI::App& app) {
  auto a = std::make_shared<ApplyArgs>();
  Command c;
  c.app = app.add_subcommand(
      "apply",
      "Raw readings -> calibrated specific force [g] (and gyro readings -> angular rate "
      "[deg/s]) with the parameters of an OUT file");
  c.app->add_option("calibration", a->calibration_json,
                    "OUT of fit, static, diagnose, filter (its rts section) or compare (batch), or a truth.json")
      ->required();
  c.app->add_option("run", a->run_yaml, "run description (run.yaml) of the readings")->required();
  c.app
      ->add_option("-o,--output", a->out_csv,
                   "output CSV: t, Wx, Wy, Wz [g] (+ omega_x, omega_y, omega_z [deg/s] with "
                   "the gyro, + angles); - for stdout")
      ->required();
  c.run = [a](Session& session) { return RunApply(*a, session); };
  return c;
}

}  // namespace triadcal
