// Fuzz target: a calibration file as `apply` reads it (strict JSON, known
// parameters and effects, bounds, one readings unit), checked against a run
// and applied to its samples by the exact inverse of the readings model.
#include <cmath>
#include <string>

#include "core/io/calibration_io.h"
#include "core/io/parameters_json.h"
#include "core/model/apply_calibration.h"
#include "fuzz/fuzz_input.h"

namespace {

// A short run on the nominal triad (174 mV/g, 1500 mV): the platform turning
// about its outer axis, gravity moving between the axes.
const triadcal::RunData& Samples() {
  static const triadcal::RunData data = [] {
    triadcal::RunData d;
    for (int k = 0; k < 40; ++k) {
      const double a = 0.15 * k;
      d.t_s.push_back(0.05 * k);
      d.lambda_rad[0].push_back(a);
      d.lambda_rad[1].push_back(0.0);
      d.w_mV[0].push_back(1500.0 + 174.0 * std::cos(a));
      d.w_mV[1].push_back(1500.0 + 3.0 * std::sin(0.7 * a));
      d.w_mV[2].push_back(1500.0 - 174.0 * std::sin(a));
    }
    return d;
  }();
  return data;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  triadcal_fuzz::ExpectOnlyInputErrors([&] {
    const triadcal::Calibration cal =
        triadcal::CalibrationFromJson(triadcal::ParseJsonStrict(text, "cal.json"), "cal.json");
    triadcal::RunDescription run;
    run.yaml_path = "run.yaml";
    triadcal::CheckCalibrationForRun(cal, run);
    triadcal::ApplyCalibration(cal, run, Samples());
  });
  return 0;
}
