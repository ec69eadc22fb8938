#include "app/apply_job.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/run_loading.h"
#include "core/io/column_mapping.h"
#include "core/io/file_util.h"
#include "core/model/apply_calibration.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

// The warning line when the median |W| is far from 1 g, "" otherwise.
std::string NormWarning(const std::string& calibration_json, const std::string& run_yaml,
                        const std::vector<Eigen::Vector3d>& W) {
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
                run_yaml.c_str(), calibration_json.c_str(), median, kMaxMedianNormError_g);
  return text;
}

// The warning line when only one of the calibration and the run has the gyro
// (the accelerometer is corrected alone), "" otherwise.
std::string GyroWarning(const std::string& calibration_json, const std::string& run_yaml,
                        const Calibration& cal, const LoadedRun& run) {
  if (cal.layout.has_gyro() && !run.data.has_gyro()) {
    return run_yaml + ": the calibration " + calibration_json +
           " has the gyro (gyro.*), but the run has no gyro readings (gx gy gz, read with a "
           "gyro block in run.yaml): accelerometer only";
  }
  if (!cal.layout.has_gyro() && run.data.has_gyro()) {
    return run_yaml + ": gx gy gz not corrected: the calibration " + calibration_json +
           " has no gyro parameters (gyro.*): accelerometer only";
  }
  return "";
}

std::string AppliedCsv(const std::string& calibration_json, const std::string& run_yaml,
                       const LoadedRun& run, const ApplyOutcome& o, const Session& session) {
  const Calibration& cal = o.calibration;
  const bool angles = !(SourceOf(run.description, "lambda1").constant &&
                        SourceOf(run.description, "lambda2").constant);
  const bool labels = run.data.has_label();
  std::string out;
  out.reserve(128 + run.data.size() * 96);
  out += "# triadcal apply: calibration " + calibration_json + " (" + cal.section +
         (cal.command.empty() ? "" : ", from " + cal.command) + "), run " + run_yaml + "\n";
  out += "# provenance: " + session.provenance.Json().dump() + "\n";
  out += "# W = specific force in the triad frame [g], an axis pointing up reads +1 g at rest:\n";
  out += "# the exact inverse of the readings model (paper eq. 1); t [s]";
  out += angles ? ", lambda1 lambda2 [deg] as recorded\n" : "\n";
  if (o.gyro) {
    out +=
        "# omega = angular rate in the triad frame [deg/s] (Earth's rate included): the exact\n"
        "# inverse of the gyro's readings model (SPEC section 10) with W of the same sample\n";
  }
  out += "t,Wx,Wy,Wz";
  if (o.gyro) out += ",omega_x,omega_y,omega_z";
  if (angles) out += ",lambda1,lambda2";
  if (labels) out += ",label";
  out += "\n";
  for (std::size_t k = 0; k < run.data.size(); ++k) {
    out += FormatDouble(run.data.t_s[k]);
    for (int i = 0; i < 3; ++i) out += "," + FormatDouble(o.W_g[k][i]);
    if (o.gyro) {
      for (int i = 0; i < 3; ++i) out += "," + FormatDouble(o.omega_rad_s[k][i] / kDegToRad);
    }
    if (angles) {
      for (int i = 0; i < 2; ++i) out += "," + FormatDouble(run.data.lambda_rad[i][k] / kDegToRad);
    }
    if (labels) out += "," + run.data.label[k];
    out += "\n";
  }
  return out;
}

}  // namespace

ApplyOutcome ApplyRun(const std::string& calibration_json, const std::string& run_yaml,
                      Session* session) {
  ApplyOutcome o;
  o.calibration = LoadCalibration(calibration_json);
  const Calibration& cal = o.calibration;
  session->RecordInput("calibration", calibration_json);
  const LoadedRun run = LoadRun(run_yaml, session);
  CheckCalibrationForRun(cal, run.description);
  o.samples = run.data.size();
  o.W_g = ApplyCalibration(cal, run.description, run.data);
  o.gyro = cal.layout.has_gyro() && run.data.has_gyro();
  if (o.gyro) o.omega_rad_s = ApplyGyroCalibration(cal, run.description, run.data, o.W_g);
  for (const std::string& w : {GyroWarning(calibration_json, run_yaml, cal, run),
                               NormWarning(calibration_json, run_yaml, o.W_g)}) {
    if (!w.empty()) o.warnings.push_back(w);
  }
  o.csv = AppliedCsv(calibration_json, run_yaml, run, o, *session);
  return o;
}

}  // namespace triadcal
