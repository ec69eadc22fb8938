#include "solvers/diagnosis/residual_analysis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/model/angle_derivatives.h"
#include "core/model/bench_model.h"

namespace triadcal {
namespace {

std::string CombinationLabel(double f, double f1, double f2, double bin_hz) {
  std::string best;
  double best_err = 1.01 * bin_hz;
  for (int a = -4; a <= 4; ++a) {
    for (int b = -4; b <= 4; ++b) {
      if (a == 0 && b == 0) continue;
      if (f2 <= 0.0 && b != 0) continue;
      const double c = a * f1 + b * f2;
      if (c <= 0.0) continue;
      const double err = std::abs(f - c);
      if (err < best_err - 1e-12) {
        best_err = err;
        auto term = [](int k, const char* name) {
          if (k == 0) return std::string();
          if (k == 1) return std::string(name);
          if (k == -1) return "-" + std::string(name);
          return std::to_string(k) + " " + name;
        };
        best = term(a, "f1");
        const std::string tb = term(b, "f2");
        if (!tb.empty())
          best += best.empty() ? tb : (tb[0] == '-' ? " - " + tb.substr(1) : " + " + tb);
      }
    }
  }
  return best;
}

using NamedSeries = std::pair<std::string, std::vector<double>>;

// What a residual is correlated with: the kinematic signals (and the
// temperature) at the samples `mids`, from the recorded angles' derivatives
// there (rec[j] at sample mids[j]).
std::vector<NamedSeries> KinematicSignals(const ModelConfig& cfg, const Eigen::VectorXd& th,
                                          const RunData& data, const std::vector<std::size_t>& mids,
                                          const std::vector<BenchAngles<double>>& rec) {
  const char* names[] = {"lambda1",
                         "lambda2",
                         "sin lambda1",
                         "cos lambda1",
                         "sin lambda2",
                         "cos lambda2",
                         "lambda1 rate",
                         "lambda2 rate",
                         "lambda1 accel",
                         "lambda2 accel",
                         "time",
                         "Wx",
                         "Wy",
                         "Wz"};
  const int n_sig = 14;
  std::vector<std::vector<double>> sig(n_sig + 1);
  for (std::size_t j = 0; j < mids.size(); ++j) {
    const std::size_t mid = mids[j];
    const BenchAngles<double>& r = rec[j];
    const BenchAngles<double> b = BenchAnglesFromRecorded<double>(cfg, th.data(), r);
    const BenchMotion<double> m = ComputeBenchMotion(cfg, th.data(), b);
    const Eigen::Vector3d W = SpecificForce_g(cfg, m.C_L2, Eigen::Vector3d::Zero().eval());
    const double l1 = r.axis[0].angle, l2 = r.axis[1].angle;
    const double v[] = {l1,
                        l2,
                        std::sin(l1),
                        std::cos(l1),
                        std::sin(l2),
                        std::cos(l2),
                        r.axis[0].rate,
                        r.axis[1].rate,
                        r.axis[0].accel,
                        r.axis[1].accel,
                        data.t_s[mid],
                        W.x(),
                        W.y(),
                        W.z()};
    for (int s = 0; s < n_sig; ++s) sig[s].push_back(v[s]);
    if (data.has_temp()) sig[n_sig].push_back(data.temp_C[mid]);
  }
  std::vector<NamedSeries> signals;
  for (int s = 0; s < n_sig; ++s) signals.push_back({names[s], sig[s]});
  if (data.has_temp()) signals.push_back({"temp_C", sig[n_sig]});
  return signals;
}

// The bench frequencies in the angles sampled every dt: lambda1's, and
// lambda2's when the inner axis moves (more than 1e-3 rad).
void BenchFrequencies(const std::vector<NamedSeries>& signals, double dt, ResidualReport* rep) {
  const std::vector<double>& l1 = signals[0].second;
  const std::vector<double>& l2 = signals[1].second;
  rep->f1_hz = DominantFrequency(l1, dt);
  double span2 = 0.0;
  for (double x : l2) span2 = std::max(span2, std::abs(x - l2[0]));
  rep->f2_hz = span2 > 1e-3 ? DominantFrequency(l2, dt) : 0.0;
}

// One channel: RMS, mean, Ljung-Box (against expected_acf when given), and
// with_spectrum its three strongest spectral peaks (bench combinations
// named) and its four strongest correlations with the signals. A channel
// enters the whiteness decision (tested) when it has an expected
// autocorrelation or no spectrum (the whitened channels).
ChannelReport AnalyseChannel(const std::string& name, const std::string& unit,
                             const std::vector<double>& x, bool with_spectrum,
                             const std::vector<double>* expected_acf,
                             const std::vector<NamedSeries>& signals, const ResidualReport& rep) {
  ChannelReport ch;
  ch.name = name;
  ch.unit = unit;
  ch.series = x;
  double ss = 0.0, sum = 0.0;
  for (double v : x) {
    ss += v * v;
    sum += v;
  }
  ch.rms = std::sqrt(ss / x.size());
  ch.mean = sum / x.size();
  ch.whiteness = LjungBox(x, 20, expected_acf);
  ch.tested = expected_acf != nullptr || !with_spectrum;
  if (with_spectrum) {
    const double bin = 1.0 / (x.size() * rep.dt_s);
    const Spectrum s = Periodogram(x, rep.dt_s);
    double total = 0.0;
    for (std::size_t k = 1; k < s.power.size(); ++k) total += s.power[k];
    std::vector<std::size_t> idx;
    for (std::size_t k = 1; k < s.power.size(); ++k) {
      const bool local_max =
          (k + 1 >= s.power.size() || s.power[k] >= s.power[k + 1]) && s.power[k] >= s.power[k - 1];
      if (local_max) idx.push_back(k);
    }
    std::sort(idx.begin(), idx.end(),
              [&](std::size_t a, std::size_t b) { return s.power[a] > s.power[b]; });
    for (std::size_t i = 0; i < std::min<std::size_t>(3, idx.size()); ++i) {
      SpectralPeak p;
      p.freq_hz = s.freq_hz[idx[i]];
      p.power_fraction = total > 0.0 ? s.power[idx[i]] / total : 0.0;
      p.combination = CombinationLabel(p.freq_hz, rep.f1_hz, rep.f2_hz, bin);
      ch.peaks.push_back(p);
    }
    for (const auto& [sname, sv] : signals) ch.correlations.push_back({sname, Correlation(x, sv)});
    // Strongest first; signals that are one on this motion (Wx and cos
    // lambda1 of a roll about y) tie to rounding and keep their order.
    auto strength = [](double r) { return std::round(std::abs(r) * 1e12); };
    std::stable_sort(ch.correlations.begin(), ch.correlations.end(),
                     [&](const auto& a, const auto& b) { return strength(a.second) > strength(b.second); });
    ch.correlations.resize(std::min<std::size_t>(4, ch.correlations.size()));
  }
  return ch;
}

// Structure: any tested channel not white, or chi2/dof significantly above
// 1; the summary names the worst channel and, of the first three (the
// residual's physical channels), the one with the strongest correlation.
void JudgeStructure(ResidualReport* rep_out) {
  ResidualReport& rep = *rep_out;
  const double chi2_excess =
      (rep.chi2_per_dof - 1.0) / std::sqrt(2.0 / std::max(1, rep.degrees_of_freedom));
  const ChannelReport* worst = nullptr;
  for (const ChannelReport& ch : rep.channels) {
    if (ch.tested && ch.whiteness.p_value < rep.whiteness_alpha &&
        (!worst || ch.whiteness.p_value < worst->whiteness.p_value)) {
      worst = &ch;
    }
  }
  rep.structure = worst != nullptr || chi2_excess > 4.0;
  if (rep.structure) {
    char buf[512];
    if (worst) {
      // Report the physical channel with the strongest correlation for words.
      const ChannelReport* a = &rep.channels[0];
      for (int c = 0; c < 3; ++c) {
        if (!rep.channels[c].correlations.empty() && !a->correlations.empty() &&
            std::abs(rep.channels[c].correlations[0].second) >
                std::abs(a->correlations[0].second)) {
          a = &rep.channels[c];
        }
      }
      std::snprintf(buf, sizeof(buf),
                    "residual not white (%s: Ljung-Box p = %.2g, lag-1 autocorrelation %.2f); "
                    "%s correlates most with %s (r = %.2f)%s%s",
                    worst->name.c_str(), worst->whiteness.p_value, worst->whiteness.rho1,
                    a->name.c_str(),
                    a->correlations.empty() ? "-" : a->correlations[0].first.c_str(),
                    a->correlations.empty() ? 0.0 : a->correlations[0].second,
                    a->peaks.empty() ? "" : ", strongest spectral peak at ",
                    a->peaks.empty()
                        ? ""
                        : (std::to_string(a->peaks[0].freq_hz).substr(0, 6) + " Hz" +
                           (a->peaks[0].combination.empty() ? std::string()
                                                            : " (" + a->peaks[0].combination + ")"))
                              .c_str());
    } else {
      std::snprintf(buf, sizeof(buf), "chi2/dof = %.3f, %.1f standard deviations above 1",
                    rep.chi2_per_dof, chi2_excess);
    }
    rep.structure_summary = buf;
  }
}

}  // namespace

ResidualReport AnalyzeResiduals(const RunDescription& run, const RunData& data,
                                const ParameterLayout& layout, const BatchResult& fit) {
  ResidualReport rep;
  rep.series_what = "process residual of each interval as a mean acceleration in the triad frame";
  rep.series_unit = "mg";
  rep.chi2_per_dof = fit.chi2_per_dof;
  rep.degrees_of_freedom = fit.degrees_of_freedom;
  const std::size_t E = fit.epoch_t.size();
  if (E < 8) return rep;
  const ModelConfig cfg = MakeModelConfig(run, layout, data);
  const Eigen::VectorXd& th = fit.estimate.theta;

  // Interval midpoints and their kinematics.
  std::vector<std::size_t> mids;
  for (std::size_t e = 1; e < E; ++e)
    mids.push_back((fit.epoch_samples[e - 1] + fit.epoch_samples[e]) / 2);
  const std::vector<BenchAngles<double>> rec = EstimateAngleDerivativesAt(data, {}, mids);
  const std::vector<NamedSeries> signals = KinematicSignals(cfg, th, data, mids, rec);

  const std::size_t M = E - 1;
  std::vector<double> acc[3];
  std::vector<double> white[6];
  for (std::size_t j = 0; j < M; ++j) {
    const std::size_t e = j + 1;
    const BenchAngles<double> b = BenchAnglesFromRecorded<double>(cfg, th.data(), rec[j]);
    const BenchMotion<double> m = ComputeBenchMotion(cfg, th.data(), b);
    const double T = fit.epoch_t[e] - fit.epoch_t[e - 1];
    const Eigen::Vector3d a_triad =
        m.C_L2.transpose() * fit.process_residual[e].head<3>() / T / cfg.g_mps2 * 1e3;
    for (int c = 0; c < 3; ++c) acc[c].push_back(a_triad[c]);
    for (int c = 0; c < 6; ++c) white[c].push_back(fit.process_whitened[e][c]);
    rep.t_s.push_back(data.t_s[mids[j]]);
  }

  rep.dt_s = (fit.epoch_t.back() - fit.epoch_t.front()) / (E - 1);
  BenchFrequencies(signals, rep.dt_s, &rep);
  const char* axes[] = {"x", "y", "z"};
  // The accel residuals (per interval, in the triad's axes) are for the eye,
  // the spectrum and the correlations: their variance follows the motion and
  // neighbouring intervals share a sample, so they are not white under the
  // model and do not enter the whiteness decision; the whitened process
  // residuals do, less the autocorrelation the fit itself leaves in them.
  for (int c = 0; c < 3; ++c) {
    rep.channels.push_back(AnalyseChannel(std::string("accel residual ") + axes[c], "mg", acc[c],
                                          true, nullptr, signals, rep));
  }
  const char* wn[] = {"whitened process V_x", "whitened process V_y", "whitened process V_z",
                      "whitened process S_x", "whitened process S_y", "whitened process S_z"};
  for (int c = 0; c < 6; ++c) {
    const std::vector<double>& expected = fit.process_whitened_expected_acf[c];
    rep.channels.push_back(AnalyseChannel(wn[c], "1", white[c], false,
                                          expected.empty() ? nullptr : &expected, signals, rep));
  }
  JudgeStructure(&rep);
  return rep;
}

ResidualReport AnalyzeGyroResiduals(const RunDescription& run, const RunData& data,
                                    const ParameterLayout& layout, const BatchResult& fit) {
  ResidualReport rep;
  rep.series_what =
      "attitude increment residual of each interval: the gyro integrated against the angle "
      "sensors, in the outer-axis frame (inner, outer, normal)";
  rep.series_unit = "arcsec";
  const BatchResult::Gyro& gy = fit.gyro;
  rep.chi2_per_dof = gy.whitened_rms * gy.whitened_rms;
  rep.degrees_of_freedom = gy.degrees_of_freedom;
  const std::size_t M = gy.mid_samples.size();
  if (!gy.present || M < 8) return rep;
  const ModelConfig cfg = MakeModelConfig(run, layout, data);
  const std::vector<BenchAngles<double>> rec = EstimateAngleDerivativesAt(data, {}, gy.mid_samples);
  const std::vector<NamedSeries> signals =
      KinematicSignals(cfg, fit.estimate.theta, data, gy.mid_samples, rec);

  constexpr double kRadToArcsec = 180.0 / 3.14159265358979323846 * 3600.0;
  std::vector<double> res[3], white[3];
  std::vector<double> spacing;
  for (std::size_t j = 0; j < M; ++j) {
    for (int c = 0; c < 3; ++c) {
      res[c].push_back(gy.residual_rad[j][c] * kRadToArcsec);
      white[c].push_back(gy.whitened[j][c]);
    }
    rep.t_s.push_back(data.t_s[gy.mid_samples[j]]);
    if (j > 0) spacing.push_back(rep.t_s[j] - rep.t_s[j - 1]);
  }
  // The intervals' spacing (the median: clipped intervals left out leave gaps).
  std::nth_element(spacing.begin(), spacing.begin() + spacing.size() / 2, spacing.end());
  rep.dt_s = spacing[spacing.size() / 2];
  BenchFrequencies(signals, rep.dt_s, &rep);
  // The increment residuals are for the eye, the spectrum and the
  // correlations (their variance follows the motion, neighbours share an
  // epoch's angle noise); the innovations whitened enter the whiteness
  // decision: white under the model, exactly.
  const char* comp[] = {"inner", "outer", "normal"};
  for (int c = 0; c < 3; ++c) {
    rep.channels.push_back(AnalyseChannel(std::string("gyro increment residual ") + comp[c],
                                          "arcsec", res[c], true, nullptr, signals, rep));
  }
  for (int c = 0; c < 3; ++c) {
    rep.channels.push_back(AnalyseChannel(std::string("whitened gyro increment ") + comp[c], "1",
                                          white[c], false, nullptr, signals, rep));
  }
  JudgeStructure(&rep);
  return rep;
}

nlohmann::json ResidualReportJson(const ResidualReport& r) {
  nlohmann::json j;
  j["chi2_per_dof"] = r.chi2_per_dof;
  j["degrees_of_freedom"] = r.degrees_of_freedom;
  j["bench_frequencies_hz"] = {r.f1_hz, r.f2_hz};
  j["structure"] = r.structure;
  j["structure_summary"] = r.structure_summary;
  nlohmann::json chans = nlohmann::json::array();
  for (const ChannelReport& c : r.channels) {
    nlohmann::json cj = {{"channel", c.name},
                         {"unit", c.unit},
                         {"rms", c.rms},
                         {"mean", c.mean},
                         {"ljung_box_q", c.whiteness.q},
                         {"ljung_box_lags", c.whiteness.lags},
                         {"ljung_box_p", c.whiteness.p_value},
                         {"lag1_autocorrelation", c.whiteness.rho1},
                         {"lag1_expected_under_model", c.whiteness.rho1_expected},
                         {"in_whiteness_test", c.tested}};
    if (!c.peaks.empty()) {
      nlohmann::json peaks = nlohmann::json::array();
      for (const SpectralPeak& p : c.peaks) {
        peaks.push_back({{"freq_hz", p.freq_hz},
                         {"power_fraction", p.power_fraction},
                         {"bench_combination", p.combination}});
      }
      cj["spectrum_peaks"] = peaks;
      nlohmann::json corr = nlohmann::json::object();
      for (const auto& [name, v] : c.correlations) corr[name] = v;
      cj["correlations"] = corr;
    }
    chans.push_back(cj);
  }
  j["channels"] = chans;
  return j;
}

}  // namespace triadcal
