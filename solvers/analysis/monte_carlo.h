// Monte Carlo of the estimators against simulated truth, and against the
// Cramer-Rao bound of the same model.
//
// For seeds s0 .. s0 + N - 1: the scenario with that seed (its truth_spread
// drawn by SampleTruth), simulated (core/simulation/simulator.h), then estimated by the
// EKF and the RTS smoother (one RunFilterSmoother: "ekf" is its first forward
// pass, "rts" the smoothed result of the last pass; with a gyro block the
// gyro's increments are its measurements, as `filter` runs it, at the run's
// reading noise or with `auto` the readings' own) and by the batch solver
// (SolveBatch, started as `fit` starts). Per parameter and estimator, with
// e_k = estimate_k - truth_k and sigma_k the estimator's own sigma:
//
//   mean_error = mean(e)              bias
//   scatter    = sqrt(mean(e^2))      what the CRB bounds (as RMS error)
//   mean_sigma = mean(sigma)          what the estimator claims
//   rms_z      = sqrt(mean((e / sigma)^2))   1 for an honest sigma
//
// and the CRB at the scenario's truth (observability.h on the noise-free run,
// with the constraints and priors the estimators use). With truth_spread on
// the constrained parameters drawn from the constraint's own sigma (as
// bench/scenarios/paper-mc.yaml does), the constraint is a correct prior and
// the CRB is the bound the scatter should reach. The relative sampling error
// of a scatter from N runs is about 1/sqrt(2N).
//
// Seeds run in parallel (solvers/estimation/parallel.h), each estimator single-threaded
// inside; the result does not depend on the number of threads. The pieces
// below (MonteCarloCrb, RunMonteCarloSeeds, SummariseMonteCarlo) let MPI ranks
// and Slurm shards run parts of the seeds and one place sum them in seed
// order: the statistics are then bit for bit those of one process.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/simulation/simulator.h"
#include "solvers/estimation/batch_solver.h"
#include "solvers/estimation/kalman_smoother.h"

namespace triadcal {

struct MonteCarloOptions {
  int runs = 100;
  std::uint64_t first_seed = 1;
  int threads = 0;  // 0: all cores
  std::vector<std::string> estimators = {"ekf", "rts", "batch"};
  ParameterLayout layout;         // what the estimators estimate
  FilterOptions filter;           // progress is ignored
  BatchOptions batch;             // threads and progress are overridden
  bool keep_runs = false;         // keep every run's errors and sigmas
  // Called after each run with (runs done, runs), from the worker threads
  // (serialised by a mutex).
  std::function<void(int, int)> progress;
};

struct EstimatorStats {
  std::string name;  // "ekf", "rts", "batch"
  int runs = 0;      // successful
  int failures = 0;  // runs where the estimator threw (their message in first_failure)
  std::string first_failure;
  Eigen::VectorXd mean_error, scatter, mean_sigma, rms_z, max_abs_z;  // SI (z unitless)
  double pooled_rms_z = 0.0;
  // Runs in which the estimator did not estimate the parameter (the batch
  // solver's held or considered, BatchResult::held and ::consider; the
  // filter's held, FilterOptions::held: kept at its nominal value); they are
  // left out of that parameter's statistics.
  Eigen::VectorXi held_runs;
};

struct MonteCarloRun {
  std::uint64_t seed = 0;
  Eigen::VectorXd truth;                // SI
  std::vector<Eigen::VectorXd> error;   // per estimator (empty when it failed; NaN when held)
  std::vector<Eigen::VectorXd> sigma;
  std::vector<std::string> failure;     // per estimator: what it threw ("" when it succeeded)
};

struct MonteCarloResult {
  ParameterLayout layout;
  Eigen::VectorXd truth;  // the scenario's, without the spread (SI)
  Eigen::VectorXd crb;    // sigma at the truth with constraints and priors (SI)
  std::vector<EstimatorStats> estimators;  // in the order asked
  std::vector<MonteCarloRun> runs;         // when keep_runs
  int threads = 1;
  double seconds = 0.0, crb_seconds = 0.0;
};

// Throws OptionError("estimators" or "runs", ...) for an unknown estimator
// name or runs < 1.
MonteCarloResult RunMonteCarlo(const Scenario& s, const MonteCarloOptions& opt);

// Throws InputError when opt.estimators is empty or names an unknown estimator.
void CheckEstimators(const std::vector<std::string>& estimators);

// The CRB at the scenario's truth (SI): the scenario's run without noise, with
// the constraints and priors the estimators use.
Eigen::VectorXd MonteCarloCrb(const Scenario& s, const MonteCarloOptions& opt);

// The runs of seeds first_seed + k for k in `indices` (in that order), on
// opt.threads threads; opt.progress gets (done, indices.size()).
std::vector<MonteCarloRun> RunMonteCarloSeeds(const Scenario& s, const MonteCarloOptions& opt,
                                              const std::vector<int>& indices);

// The statistics of `runs` (summed in the order given) into res->estimators;
// res->layout must be set.
void SummariseMonteCarlo(const std::vector<std::string>& estimators,
                         const std::vector<MonteCarloRun>& runs, MonteCarloResult* res);

}  // namespace triadcal
