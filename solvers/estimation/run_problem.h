// What every estimator of a run shares: the model configuration, the recorded
// angles with their derivatives, the measurement epochs, the priors, the
// constraints as rows over theta, and the noise the run declares, turned into
// the variances the process and measurement models need.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/model/angle_derivatives.h"
#include "core/model/bench_model.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"
#include "solvers/estimation/inertial_increments.h"
#include "core/model/priors.h"

namespace triadcal {

// A constraint as a row over theta: c . theta = value +- sigma (SI).
struct ConstraintRow {
  Eigen::VectorXd c;
  double value = 0.0, sigma = 0.0;
};

// The interval between measurement epochs every estimator and analysis uses
// unless the user says otherwise [s]. 0.5 s halves the errors-in-variables
// bias of the scale factors against 0.2 s for +0.8 % sigma (README).
constexpr double kDefaultEpoch_s = 0.5;
// The gyro's increments are compared with the angles this often [s]: the
// angle noise costs the gyro's estimates in proportion to the interval
// (gyro_term.h), the cost grows as its inverse.
constexpr double kGyroEpoch_s = 0.1;

// The estimation set-up of one run, built once (BuildRunProblem) and handed to
// every estimator: the model configuration, the data with their derivatives,
// the epochs, the priors, the constraints, the noise, and which parameters are
// estimated (free) and which are held at their nominal values (held: absent
// from every solved problem, state_space_model.h).
struct RunProblem {
  ModelConfig cfg;
  SampleSeries series;
  std::vector<std::size_t> epochs;  // sample index of each epoch
  // The gyro's epochs (gyro_term.h), every kGyroEpoch_s: empty without a gyro.
  std::vector<std::size_t> gyro_epochs;
  Prior prior;
  std::vector<ConstraintRow> constraints;
  // Noise of one sample: the reading noise of each channel [mV] (declared,
  // or estimated: noise_estimation.h), and the part that acts alike on every
  // axis of L [m^2/s^4] (angle noise rotating g).
  Eigen::Vector3d noise_mV = Eigen::Vector3d::Constant(2.0);
  double isotropic_var = 0.0;
  // The gyro's rate noise per sample, each channel [rad/s] (gyro_term.h): the
  // declared figures, the start of its estimate.
  Eigen::Vector3d gyro_noise_rad_s = Eigen::Vector3d::Constant(0.05 * kDegToRad);
  double sigma_angle = 0.0;   // [rad]
  double sigma_rate = 0.0;    // [rad/s], of lambda' from the angles
  int n = 0;                  // parameters of the layout
  std::vector<int> free;      // estimated, ascending (all by default)
  std::vector<int> held;      // held at theta_held, ascending
  Eigen::VectorXd theta_held;  // n: the values of the held parameters (nominal)

  // Holds these parameters (indices into the layout) at theta_held; the
  // others are free.
  void Hold(const std::vector<int>& indices);
};

struct RunPass;  // run_evaluation.h

// Work on one run that no parameter layout changes, for the fits of several
// layouts of it (diagnose's loop; on a real 25-min, 100-Hz run about 40 and
// 20 ms a fit): the recorded angles' rates and accelerations, and the noise
// weights' reference pass at the nominal values (WeightsPass: every effect is
// nominal at zero, where it changes neither the angles nor the triad's
// axes, and the reduction reads only the scale factors of its theta). Each
// part is formed by the first fit that asks for it and kept while later ones
// ask for the same run data, epochs, derivative options and nominal values;
// one that differs is formed anew and replaces it. Not for concurrent use.
class SharedRunWork {
 public:
  using Series = std::shared_ptr<const std::vector<BenchAngles<double>>>;
  // The derivatives at `at` (every sample when empty), formed on `threads`
  // threads (0: all cores).
  Series Derivatives(const RunData& data, const AngleDerivativeOptions& options,
                     const std::vector<std::size_t>& at, int threads = 0);
  // WeightsPass(p, p.prior.mean) (run_evaluation.cpp).
  std::shared_ptr<const RunPass> Weights(const RunProblem& p, int threads);

 private:
  struct SeriesEntry {
    const RunData* data = nullptr;
    double half_window_s = 0.0;
    std::vector<std::size_t> at;
    Series series;
  };
  std::vector<SeriesEntry> series_;  // at most one every-sample and one at-epochs entry
  struct WeightsEntry {
    const RunData* data = nullptr;
    std::vector<std::size_t> epochs;
    Eigen::VectorXd nominal;  // the base parameters' nominal values
    double sigma_angle = 0.0, sigma_rate = 0.0, isotropic_var = 0.0;
    std::shared_ptr<const RunPass> pass;
  };
  WeightsEntry weights_;
};

// The run's constraints as rows over the layout's theta. Throws InputError
// when a constraint names a parameter that is not in the layout.
std::vector<ConstraintRow> ResolveConstraints(const RunDescription& run,
                                              const ParameterLayout& layout);

// Throws InputError for a run too short for epoch_s, or a constraint naming a
// parameter that is not in the layout.
// With `shared`, the angles' derivatives come from it (formed there once).
// threads: how many the angles' derivatives are formed on (0: all cores).
RunProblem BuildRunProblem(const RunDescription& run, const RunData& data,
                           const ParameterLayout& layout, double epoch_s,
                           const AngleDerivativeOptions& derivatives,
                           SharedRunWork* shared = nullptr, int threads = 0);

// p read as a recorded run's Fisher information needs (observability, single
// or joint): the readings the model predicts at theta for each sample's
// recorded motion (SampleSeries::Readings::kPredicted, the angles' derivatives
// at every sample of `data`, p's run), not the recorded readings, whose noise
// the Jacobian would take for the specific force a parameter multiplies.
void ReadPredictedReadingsInMotion(RunProblem* p, const RunData& data,
                                   const AngleDerivativeOptions& derivatives, int threads = 0);

// Sample indices of the measurement epochs: the first sample, then the first
// sample at least epoch_s after the previous epoch, and the last sample.
std::vector<std::size_t> ChooseEpochs(const RunData& data, double epoch_s);

// The samples idx of d (labels are not carried).
RunData SelectSamples(const RunData& d, const std::vector<std::size_t>& idx);

// Every m-th sample of a run (m >= 1), for quick initialisers.
RunData Decimate(const RunData& data, std::size_t m);

}  // namespace triadcal
