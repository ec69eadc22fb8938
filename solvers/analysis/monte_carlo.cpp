#include "solvers/analysis/monte_carlo.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <numeric>

#include "core/model/errors.h"
#include "core/model/sample_noise.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/estimation/parallel.h"

namespace triadcal {

void CheckEstimators(const std::vector<std::string>& estimators) {
  for (const std::string& e : estimators) {
    if (e != "ekf" && e != "rts" && e != "batch") {
      throw OptionError("estimators", "unknown estimator '" + e + "' (ekf, rts, batch)");
    }
  }
  if (estimators.empty()) throw OptionError("estimators", "none given (ekf, rts, batch)");
}

Eigen::VectorXd MonteCarloCrb(const Scenario& s, const MonteCarloOptions& opt) {
  DesignOptions dopt;
  dopt.epoch_s = opt.batch.epoch_s;
  dopt.derivatives = opt.batch.derivatives;
  dopt.observability.threads = opt.threads > 0 ? opt.threads : DefaultThreads();
  const ObservabilityResult obs = AnalyseScenario(s, opt.layout, dopt);
  return obs.with_constraints.cov.diagonal().cwiseMax(0.0).cwiseSqrt();
}

std::vector<MonteCarloRun> RunMonteCarloSeeds(const Scenario& s, const MonteCarloOptions& opt,
                                              const std::vector<int>& indices) {
  CheckEstimators(opt.estimators);
  bool want_filter = false;
  for (const std::string& e : opt.estimators) want_filter |= e == "ekf" || e == "rts";
  const ParameterLayout& layout = opt.layout;
  const std::size_t E = opt.estimators.size();
  const int threads = opt.threads > 0 ? opt.threads : DefaultThreads();

  std::vector<MonteCarloRun> runs(indices.size());
  std::mutex mutex;
  int done = 0;
  ParallelFor(indices.size(), threads, [&](std::size_t slot) {
    Scenario q = s;
    q.seed = opt.first_seed + static_cast<std::uint64_t>(indices[slot]);
    SampleTruth(&q);
    const RunData data = Simulate(q);
    MonteCarloRun& run = runs[slot];
    run.seed = q.seed;
    run.truth = TruthInLayout(q, layout);
    run.error.assign(E, Eigen::VectorXd());
    run.sigma.assign(E, Eigen::VectorXd());
    run.failure.assign(E, std::string());
    FilterResult fr;
    std::string filter_failure;
    FilterOptions fo = opt.filter;
    fo.progress = nullptr;
    // Single-threaded inside (the seeds are the parallel work). With a gyro
    // block the filter takes the gyro's increments as `filter` does (its
    // parameters in the state), at the declared reading noise or, with
    // `auto`, the readings' own (what `filter` runs at).
    fo.threads = 1;
    if (want_filter) {
      try {
        fr = RunFilterSmoother(WithReadingNoise(q.run, data), data, layout, fo);
      } catch (const std::exception& e) {
        filter_failure = e.what();
      }
    }
    for (std::size_t j = 0; j < E; ++j) {
      const std::string& name = opt.estimators[j];
      const Estimate* est = nullptr;
      BatchResult br;
      // What the estimator did not estimate (held; for batch also considered:
      // at nominal with the prior's uncertainty): no error to judge against a sigma.
      std::vector<std::string> not_estimated;
      if (name == "batch") {
        BatchOptions bo = opt.batch;
        bo.threads = 1;
        bo.progress = nullptr;
        try {
          br = SolveBatch(q.run, data, layout, bo);
          est = &br.estimate;
          not_estimated = br.held;
          not_estimated.insert(not_estimated.end(), br.consider.begin(), br.consider.end());
        } catch (const std::exception& e) {
          run.failure[j] = e.what();
        }
      } else if (filter_failure.empty()) {
        est = name == "ekf" ? &fr.ekf : &fr.rts;
        not_estimated = fo.held;
      } else {
        run.failure[j] = filter_failure;
      }
      if (est) {
        run.error[j] = est->theta - run.truth;
        run.sigma[j] = est->cov.diagonal().cwiseMax(0.0).cwiseSqrt();
        for (const std::string& h : not_estimated) {
          const int i = layout.IndexOf(h);
          if (i >= 0) run.error[j][i] = std::nan("");
        }
      }
    }
    if (opt.progress) {
      std::lock_guard<std::mutex> lock(mutex);
      opt.progress(++done, static_cast<int>(indices.size()));
    }
  });
  return runs;
}

void SummariseMonteCarlo(const std::vector<std::string>& estimators,
                         const std::vector<MonteCarloRun>& runs, MonteCarloResult* res) {
  const int n = res->layout.size();
  res->estimators.clear();
  for (std::size_t j = 0; j < estimators.size(); ++j) {
    EstimatorStats st;
    st.name = estimators[j];
    Eigen::VectorXd se = Eigen::VectorXd::Zero(n), se2 = Eigen::VectorXd::Zero(n);
    Eigen::VectorXd ss = Eigen::VectorXd::Zero(n), sz2 = Eigen::VectorXd::Zero(n);
    Eigen::VectorXd used = Eigen::VectorXd::Zero(n);
    st.max_abs_z = Eigen::VectorXd::Zero(n);
    st.held_runs = Eigen::VectorXi::Zero(n);
    for (const MonteCarloRun& run : runs) {
      if (run.error[j].size() == 0) {
        ++st.failures;
        if (st.first_failure.empty()) {
          st.first_failure = "seed " + std::to_string(run.seed) + ": " + run.failure[j];
        }
        continue;
      }
      ++st.runs;
      const Eigen::VectorXd& e = run.error[j];
      const Eigen::VectorXd& sg = run.sigma[j];
      for (int i = 0; i < n; ++i) {
        if (std::isnan(e[i])) {
          ++st.held_runs[i];
          continue;
        }
        const double z = e[i] / std::max(sg[i], 1e-300);
        used[i] += 1.0;
        se[i] += e[i];
        se2[i] += e[i] * e[i];
        ss[i] += sg[i];
        sz2[i] += z * z;
        st.max_abs_z[i] = std::max(st.max_abs_z[i], std::abs(z));
      }
    }
    const Eigen::VectorXd m = used.cwiseMax(1.0);
    st.mean_error = se.cwiseQuotient(m);
    st.scatter = se2.cwiseQuotient(m).cwiseSqrt();
    st.mean_sigma = ss.cwiseQuotient(m);
    st.rms_z = sz2.cwiseQuotient(m).cwiseSqrt();
    st.pooled_rms_z = std::sqrt(sz2.sum() / std::max(1.0, used.sum()));
    res->estimators.push_back(st);
  }
}

MonteCarloResult RunMonteCarlo(const Scenario& s, const MonteCarloOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  if (opt.runs < 1) throw OptionError("runs", "at least 1 run, got " + std::to_string(opt.runs));
  CheckEstimators(opt.estimators);
  MonteCarloResult res;
  res.layout = opt.layout;
  res.truth = TruthInLayout(s, opt.layout);
  res.threads = opt.threads > 0 ? opt.threads : DefaultThreads();
  res.crb = MonteCarloCrb(s, opt);
  res.crb_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<int> all(opt.runs);
  std::iota(all.begin(), all.end(), 0);
  std::vector<MonteCarloRun> runs = RunMonteCarloSeeds(s, opt, all);
  SummariseMonteCarlo(opt.estimators, runs, &res);
  if (opt.keep_runs) res.runs = std::move(runs);
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace triadcal
