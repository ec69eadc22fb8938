#include "solvers/estimation/run_problem.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/model/errors.h"
#include "solvers/estimation/parallel.h"

namespace triadcal {

std::vector<std::size_t> ChooseEpochs(const RunData& data, double epoch_s) {
  std::vector<std::size_t> ep;
  const std::size_t n = data.size();
  if (n == 0) return ep;
  ep.push_back(0);
  for (std::size_t k = 1; k < n; ++k) {
    if (data.t_s[k] - data.t_s[ep.back()] >= epoch_s - 1e-9) ep.push_back(k);
  }
  if (ep.back() != n - 1) {
    // Merge a short last interval into the previous one.
    if (ep.size() > 1 && data.t_s[n - 1] - data.t_s[ep.back()] < 0.5 * epoch_s) {
      ep.back() = n - 1;
    } else {
      ep.push_back(n - 1);
    }
  }
  return ep;
}

RunData SelectSamples(const RunData& d, const std::vector<std::size_t>& idx) {
  RunData out;
  auto pick = [&idx](const std::vector<double>& v) {
    std::vector<double> o;
    if (v.empty()) return o;
    o.reserve(idx.size());
    for (std::size_t k : idx) o.push_back(v[k]);
    return o;
  };
  out.t_s = pick(d.t_s);
  for (int i = 0; i < 2; ++i) {
    out.lambda_rad[i] = pick(d.lambda_rad[i]);
    out.rate_rad_s[i] = pick(d.rate_rad_s[i]);
  }
  for (int i = 0; i < 3; ++i) out.w_mV[i] = pick(d.w_mV[i]);
  for (int i = 0; i < 3; ++i) out.gyro_rad_s[i] = pick(d.gyro_rad_s[i]);
  if (!d.gyro_clipped.empty()) {
    for (std::size_t k : idx) out.gyro_clipped.push_back(d.gyro_clipped[k]);
  }
  out.temp_C = pick(d.temp_C);
  return out;
}

RunData Decimate(const RunData& d, std::size_t m) {
  if (m <= 1) return d;
  std::vector<std::size_t> idx;
  for (std::size_t k = 0; k < d.size(); k += m) idx.push_back(k);
  RunData out = SelectSamples(d, idx);
  // A kept sample stands for those up to the next one: clipped if one of them is.
  for (std::size_t j = 0; j < out.gyro_clipped.size(); ++j) {
    for (std::size_t k = idx[j]; k < std::min(d.size(), idx[j] + m); ++k) {
      if (d.gyro_clipped[k]) out.gyro_clipped[j] = 1;
    }
  }
  return out;
}

std::vector<ConstraintRow> ResolveConstraints(const RunDescription& run,
                                              const ParameterLayout& layout) {
  std::vector<ConstraintRow> rows;
  for (const Constraint& k : run.constraints) {
    ConstraintRow row{Eigen::VectorXd::Zero(layout.size()), k.value_si, k.sigma_si};
    for (const auto& [name, coef] : k.terms) {
      const int i = layout.IndexOf(name);
      if (i < 0) {
        throw InputError(run.yaml_path + ": constraints: '" + k.expr + "' names '" + name +
                         "', which is not estimated in this run (add its effect to the estimated ones)");
      }
      row.c[i] += coef;
    }
    rows.push_back(row);
  }
  return rows;
}

namespace {

// The angles' rates and accelerations at the samples `at` (every sample when
// empty), each an independent local fit: in blocks on `threads` threads (0:
// all cores; at every sample, a layout with angle_latency: 0.075 s of a real
// 25-min 100-Hz run on one core). The same numbers as on one.
std::vector<BenchAngles<double>> DerivativesOnCores(const RunData& data,
                                                    const AngleDerivativeOptions& options,
                                                    const std::vector<std::size_t>& at,
                                                    int threads) {
  std::vector<std::size_t> every;
  if (at.empty()) {
    every.resize(data.size());
    for (std::size_t k = 0; k < every.size(); ++k) every[k] = k;
  }
  const std::vector<std::size_t>& where = at.empty() ? every : at;
  constexpr std::size_t kBlock = 4096;
  const std::size_t blocks = (where.size() + kBlock - 1) / kBlock;
  std::vector<BenchAngles<double>> out(where.size());
  options.Check();
  ParallelFor(blocks, threads > 0 ? threads : DefaultThreads(), [&](std::size_t b) {
    const std::size_t begin = b * kBlock, end = std::min(where.size(), begin + kBlock);
    const std::vector<std::size_t> part(where.begin() + begin, where.begin() + end);
    const std::vector<BenchAngles<double>> d = EstimateAngleDerivativesAt(data, options, part);
    std::copy(d.begin(), d.end(), out.begin() + begin);
  });
  return out;
}

}  // namespace

SharedRunWork::Series SharedRunWork::Derivatives(const RunData& data,
                                                 const AngleDerivativeOptions& options,
                                                 const std::vector<std::size_t>& at,
                                                 int threads) {
  for (const SeriesEntry& e : series_) {
    if (e.data == &data && e.half_window_s == options.half_window_s && e.at == at) return e.series;
  }
  SeriesEntry e{&data, options.half_window_s, at, nullptr};
  e.series = std::make_shared<const std::vector<BenchAngles<double>>>(
      DerivativesOnCores(data, options, at, threads));
  // One entry of each kind (every sample, at the epochs): a new one replaces its kind's.
  series_.erase(std::remove_if(series_.begin(), series_.end(),
                               [&](const SeriesEntry& o) { return o.at.empty() == at.empty(); }),
                series_.end());
  series_.push_back(e);
  return e.series;
}

void ReadPredictedReadingsInMotion(RunProblem* p, const RunData& data,
                                   const AngleDerivativeOptions& derivatives, int threads) {
  SharedRunWork every_sample;
  p->series.at.clear();
  p->series.derivatives = every_sample.Derivatives(data, derivatives, {}, threads);
  p->series.readings = SampleSeries::Readings::kPredicted;
}

RunProblem BuildRunProblem(const RunDescription& run, const RunData& data,
                           const ParameterLayout& layout, double epoch_s,
                           const AngleDerivativeOptions& derivatives, SharedRunWork* shared,
                           int threads) {
  if (!(epoch_s > 0.0)) throw OptionError("epoch_s", "must be > 0");
  RunProblem p;
  p.cfg = MakeModelConfig(run, layout, data);
  p.series.run = &data;
  p.epochs = ChooseEpochs(data, epoch_s);
  if (p.epochs.size() < 3) {
    throw InputError(run.data_path + ": run too short (" + std::to_string(p.epochs.size()) +
                     " epochs of " + std::to_string(epoch_s) + " s; at least 3 needed)");
  }
  if (!NeedsRatesAtEverySample(layout)) p.series.at = p.epochs;
  if (shared) {
    p.series.derivatives = shared->Derivatives(data, derivatives, p.series.at, threads);
  } else {
    p.series.derivatives = std::make_shared<const std::vector<BenchAngles<double>>>(
        DerivativesOnCores(data, derivatives, p.series.at, threads));
  }
  p.prior = MakePrior(run, layout);
  p.n = layout.size();
  p.theta_held = p.prior.mean;
  p.Hold({});
  p.constraints = ResolveConstraints(run, layout);
  p.noise_mV = run.ChannelNoise_mV();
  if (run.gyro) p.gyro_noise_rad_s = run.gyro->noise_rad_s;
  if (layout.has_gyro() && data.has_gyro()) {
    p.gyro_epochs = ChooseEpochs(data, std::min(epoch_s, kGyroEpoch_s));
  }
  p.isotropic_var = IsotropicSampleVariance(run.angle_noise_rad, run.g_mps2);
  p.sigma_angle = run.angle_noise_rad;
  const double dt =
      (data.t_s.back() - data.t_s.front()) / std::max<std::size_t>(1, data.size() - 1);
  p.sigma_rate = data.has_rates() ? 0.0 : RateNoiseGain(dt, derivatives) * p.sigma_angle;
  return p;
}

void RunProblem::Hold(const std::vector<int>& indices) {
  std::vector<bool> is_held(n, false);
  for (int i : indices) is_held.at(i) = true;
  free.clear();
  held.clear();
  for (int i = 0; i < n; ++i) (is_held[i] ? held : free).push_back(i);
}

}  // namespace triadcal
