// `triadcal apply CALIBRATION.json RUN.yaml -o corrected.csv`: raw readings ->
// calibrated specific force [g] in the triad frame, by the exact inverse of the
// readings model (core/model/apply_calibration.h), and, when both the
// calibration and the run have the gyro (SPEC section 10), gyro readings ->
// angular rate [deg/s] in the triad frame.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/io/calibration_io.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "tools/command_util.h"
#include "tools/commands.h"
#include "app/output_guard.h"

namespace triadcal {
namespace {

struct ApplyArgs {
  std::string calibration_json, run_yaml, out_csv;
};

// The corrected specific force of a run on a bench (or held still) has |W|
// near 1 g: the dynamic terms of a bench add < 0.03 g. A median off by more
// than this says the calibration does not fit the run.
constexpr double kMaxMedianNormError_g = 0.1;

// The warning line when the median |W| is far from 1 g, "" otherwise.
std::string NormWarning(const ApplyArgs& a, const std::vector<Eigen::Vector3d>& W) {
  if (W.empty()) return "";
  std::vector<double> norm(W.size());
  for (std::size_t k = 0; k < W.size(); ++k) norm[k] = W[k].norm();
  std::nth_element(norm.begin(), norm.begin() + norm.size() / 2, norm.end());
  const double median = norm[norm.size() / 2];
  if (std::abs(median - 1.0) <= kMaxMedianNormError_g) return "";
  char text[400];
  std::snprintf(text, sizeof(text),
                "%s: corrected with %s, |W| has the median %.4g g, where a bench at rest gives "
                "1 g (bound +-%.2g g): a calibration of another sensor, in other units or for "
                "another mounting?",
                a.run_yaml.c_str(), a.calibration_json.c_str(), median, kMaxMedianNormError_g);
  return text;
}

// The warning line when only one of the calibration and the run has the gyro
// (the accelerometer is corrected alone), "" otherwise.
std::string GyroWarning(const ApplyArgs& a, const Calibration& cal, const LoadedRun& run) {
  if (cal.layout.has_gyro() && !run.data.has_gyro()) {
    return a.run_yaml + ": the calibration " + a.calibration_json +
           " has the gyro (gyro.*), but the run has no gyro readings (gx gy gz, read with a "
           "gyro block in run.yaml): accelerometer only";
  }
  if (!cal.layout.has_gyro() && run.data.has_gyro()) {
    return a.run_yaml + ": gx gy gz not corrected: the calibration " + a.calibration_json +
           " has no gyro parameters (gyro.*): accelerometer only";
  }
  return "";
}

int RunApply(const ApplyArgs& a, Session& session) {
  const bool to_stdout = IsStdout(a.out_csv);
  if (!to_stdout) CheckOutputPath(a.out_csv);
  const Calibration cal = LoadCalibration(a.calibration_json);
  session.provenance.RecordInput("calibration", a.calibration_json);
  const LoadedRun run = LoadRun(a.run_yaml, &session);
  CheckCalibrationForRun(cal, run.description);
  if (!to_stdout) CheckOverwrite(a.out_csv, session);
  const std::vector<Eigen::Vector3d> W = ApplyCalibration(cal, run.description, run.data);
  const bool gyro = cal.layout.has_gyro() && run.data.has_gyro();
  const std::vector<Eigen::Vector3d> omega_rad_s =
      gyro ? ApplyGyroCalibration(cal, run.description, run.data, W)
           : std::vector<Eigen::Vector3d>();
  for (const std::string& warning : {GyroWarning(a, cal, run), NormWarning(a, W)}) {
    if (!warning.empty()) std::fprintf(stderr, "triadcal: warning: %s\n", OneLine(warning).c_str());
  }
  const bool angles = !(SourceOf(run.description, "lambda1").constant &&
                        SourceOf(run.description, "lambda2").constant);
  const bool labels = run.data.has_label();

  std::string out;
  out.reserve(128 + run.data.size() * 96);
  out += "# triadcal apply: calibration " + a.calibration_json + " (" + cal.section +
         (cal.command.empty() ? "" : ", from " + cal.command) + "), run " + a.run_yaml + "\n";
  out += "# provenance: " + session.provenance.Json().dump() + "\n";
  out += "# W = specific force in the triad frame [g], an axis pointing up reads +1 g at rest:\n";
  out += "# the exact inverse of the readings model (paper eq. 1); t [s]";
  out += angles ? ", lambda1 lambda2 [deg] as recorded\n" : "\n";
  if (gyro) {
    out +=
        "# omega = angular rate in the triad frame [deg/s] (Earth's rate included): the exact\n"
        "# inverse of the gyro's readings model (SPEC section 10) with W of the same sample\n";
  }
  out += "t,Wx,Wy,Wz";
  if (gyro) out += ",omega_x,omega_y,omega_z";
  if (angles) out += ",lambda1,lambda2";
  if (labels) out += ",label";
  out += "\n";
  for (std::size_t k = 0; k < run.data.size(); ++k) {
    out += FormatDouble(run.data.t_s[k]);
    for (int i = 0; i < 3; ++i) out += "," + FormatDouble(W[k][i]);
    if (gyro) {
      for (int i = 0; i < 3; ++i) out += "," + FormatDouble(omega_rad_s[k][i] / kDegToRad);
    }
    if (angles) {
      for (int i = 0; i < 2; ++i) out += "," + FormatDouble(run.data.lambda_rad[i][k] / kDegToRad);
    }
    if (labels) out += "," + run.data.label[k];
    out += "\n";
  }
  WriteOutput(a.out_csv, out);
  if (to_stdout) return 0;  // stdout holds the CSV
  std::printf("apply: %zu samples, %d parameters from %s (%s)%s\nwrote %s\n", run.data.size(),
              cal.layout.size(), a.calibration_json.c_str(), cal.section.c_str(),
              gyro ? "; accelerometer and gyro" : "", a.out_csv.c_str());
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
