// Rates and angular accelerations of the bench from the recorded angles.
//
// The paper's block B2 needs lambda' (V_DU = w x S), and the angle-stage effects
// need lambda''. When the run has no rate columns they are estimated by a local
// cubic least-squares fit (Savitzky-Golay) over a window of +-half_window_s
// around each sample, using the real time stamps:
//
//   lambda(t_k + s) ~ c0 + c1 s + c2 s^2 + c3 s^3,   lambda' = c1, lambda'' = 2 c2
//
// Errors: a cubic fit has no bias up to the 4th derivative; for lambda' the next
// term is ~ lambda^(5) h^4 / 10 (3e-6 rad/s for the paper's profile and
// h = 0.1 s). White angle noise sigma gives lambda' noise ~ 2.1 sigma / (h sqrt(N))
// with N samples in the window (RateNoiseGain returns the exact factor).
#pragma once

#include <vector>

#include "core/model/bench_model.h"
#include "core/model/run_data.h"

namespace triadcal {

struct AngleDerivativeOptions {
  double half_window_s = 0.1;
  // Bounds of half_window_s [s]: below 1 ms the window holds one sample at
  // any bench rate (the fit widens it to 5 samples, so nothing is gained);
  // above 2 s it smooths over the bench's swings (periods of seconds), and
  // every window spans most of a short run (0 s made the fit divide by 0, 1e6 s
  // ran for minutes).
  static constexpr double kMinHalfWindow_s = 1e-3;
  static constexpr double kMaxHalfWindow_s = 2.0;
  // Throws OptionError("half_window_s", ...) unless half_window_s is finite
  // and within the bounds; the functions below call it first.
  void Check() const;
};

// Per sample: recorded angle (as is), rate and angular acceleration of both
// axes. With rate columns, the rate is taken from the file and the acceleration
// is the local-fit derivative of the rate.
std::vector<BenchAngles<double>> EstimateAngleDerivatives(const RunData& run,
                                                          const AngleDerivativeOptions& opt);

// The same at the listed samples alone, one entry per index in `at` (the base
// model needs lambda' only at the measurement epochs: a long run is not
// held again sample by sample).
std::vector<BenchAngles<double>> EstimateAngleDerivativesAt(const RunData& run,
                                                            const AngleDerivativeOptions& opt,
                                                            const std::vector<std::size_t>& at);

// True when the model needs lambda', lambda'' at every sample (effects of the
// angle stage, and the size effect's per-axis kinematics in block B1).
bool NeedsRatesAtEverySample(const ParameterLayout& layout);

// sigma(lambda') / sigma(lambda) of the local fit at an interior sample of a
// uniformly sampled run with interval dt_s [1/s].
double RateNoiseGain(double dt_s, const AngleDerivativeOptions& opt);

}  // namespace triadcal
