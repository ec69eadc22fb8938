#include "solvers/analysis/monte_carlo.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>

#include "core/model/errors.h"
#include "solvers/analysis/experiment_design.h"
#include "solvers/estimation/parallel.h"

namespace triadcal {

MonteCarloResult RunMonteCarlo(const Scenario& s, const MonteCarloOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  if (opt.runs < 1) throw OptionError("runs", "at least 1 run, got " + std::to_string(opt.runs));
  bool want_filter = false;
  for (const std::string& e : opt.estimators) {
    if (e == "ekf" || e == "rts") {
      want_filter = true;
    } else if (e != "batch") {
      throw OptionError("estimators", "unknown estimator '" + e + "' (ekf, rts, batch)");
    }
  }
  if (opt.estimators.empty()) throw OptionError("estimators", "none given (ekf, rts, batch)");
  const ParameterLayout& layout = opt.layout;
  const int n = layout.size();
  const std::size_t E = opt.estimators.size();

  MonteCarloResult res;
  res.layout = layout;
  res.truth = TruthInLayout(s, layout);
  res.threads = opt.threads > 0 ? opt.threads : DefaultThreads();

  // The CRB at the truth: the scenario's run without noise.
  {
    DesignOptions dopt;
    dopt.epoch_s = opt.batch.epoch_s;
    dopt.derivatives = opt.batch.derivatives;
    dopt.observability.threads = res.threads;
    const ObservabilityResult obs = AnalyseScenario(s, layout, dopt);
    res.crb = obs.with_constraints.cov.diagonal().cwiseMax(0.0).cwiseSqrt();
    res.crb_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  std::vector<MonteCarloRun> runs(opt.runs);
  std::vector<std::vector<std::string>> failures(opt.runs, std::vector<std::string>(E));
  std::mutex mutex;
  int done = 0;
  ParallelFor(static_cast<std::size_t>(opt.runs), res.threads, [&](std::size_t k) {
    Scenario q = s;
    q.seed = opt.first_seed + k;
    SampleTruth(&q);
    const RunData data = Simulate(q);
    MonteCarloRun& run = runs[k];
    run.seed = q.seed;
    run.truth = TruthInLayout(q, layout);
    run.error.assign(E, Eigen::VectorXd());
    run.sigma.assign(E, Eigen::VectorXd());
    FilterResult fr;
    std::string filter_failure;
    if (want_filter) {
      FilterOptions fo = opt.filter;
      fo.progress = nullptr;
      try {
        fr = RunFilterSmoother(q.run, data, layout, fo);
      } catch (const std::exception& e) {
        filter_failure = e.what();
      }
    }
    for (std::size_t j = 0; j < E; ++j) {
      const std::string& name = opt.estimators[j];
      const Estimate* est = nullptr;
      BatchResult br;
      if (name == "batch") {
        BatchOptions bo = opt.batch;
        bo.threads = 1;
        bo.progress = nullptr;
        try {
          br = SolveBatch(q.run, data, layout, bo);
          est = &br.estimate;
        } catch (const std::exception& e) {
          failures[k][j] = e.what();
        }
      } else if (filter_failure.empty()) {
        est = name == "ekf" ? &fr.ekf : &fr.rts;
      } else {
        failures[k][j] = filter_failure;
      }
      if (est) {
        run.error[j] = est->theta - run.truth;
        run.sigma[j] = est->cov.diagonal().cwiseMax(0.0).cwiseSqrt();
        if (name == "batch") {
          for (const std::string& h : br.held) {
            const int i = layout.IndexOf(h);
            if (i >= 0) run.error[j][i] = std::nan("");
          }
        }
      }
    }
    if (opt.progress) {
      std::lock_guard<std::mutex> lock(mutex);
      opt.progress(++done, opt.runs);
    }
  });

  for (std::size_t j = 0; j < E; ++j) {
    EstimatorStats st;
    st.name = opt.estimators[j];
    Eigen::VectorXd se = Eigen::VectorXd::Zero(n), se2 = Eigen::VectorXd::Zero(n);
    Eigen::VectorXd ss = Eigen::VectorXd::Zero(n), sz2 = Eigen::VectorXd::Zero(n);
    Eigen::VectorXd used = Eigen::VectorXd::Zero(n);
    st.max_abs_z = Eigen::VectorXd::Zero(n);
    st.held_runs = Eigen::VectorXi::Zero(n);
    for (int k = 0; k < opt.runs; ++k) {
      if (runs[k].error[j].size() == 0) {
        ++st.failures;
        if (st.first_failure.empty()) {
          st.first_failure = "seed " + std::to_string(runs[k].seed) + ": " + failures[k][j];
        }
        continue;
      }
      ++st.runs;
      const Eigen::VectorXd& e = runs[k].error[j];
      const Eigen::VectorXd& sg = runs[k].sigma[j];
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
    res.estimators.push_back(st);
  }
  if (opt.keep_runs) res.runs = std::move(runs);
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace triadcal
