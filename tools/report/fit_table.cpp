#include "tools/report/fit_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/io/file_util.h"
#include "tools/report/value_format.h"

namespace triadcal {

void PrintParameterTable(const ParameterLayout& layout, const BatchResult& r,
                         const FitReport& rep) {
  // Values to the digit of their sigma (value_format.h).
  std::printf("%-26s %16s %10s %10s  %s\n", "parameter", "value", "sigma", "start", "unit");
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& pi = layout.info(i);
    const double f = pi.si_per_unit;
    // A held or considered parameter has no estimate and no sigma: "-".
    const double sigma = rep.held.count(pi.name) || rep.consider.count(pi.name)
                             ? 0.0
                             : std::sqrt(std::max(0.0, r.estimate.cov(i, i))) / f;
    const ValueText v = FormatWithSigma(r.estimate.theta[i] / f, sigma);
    std::string label;
    if (rep.held.count(pi.name)) {
      label = "  (held at nominal)";
    } else if (rep.consider.count(pi.name)) {
      char why[120];
      std::snprintf(why, sizeof(why), "  (not determined: nominal, prior +-%.3g carried)",
                    r.prior.sigma[i] / f);
      label = why;
    } else if (const auto w = rep.with_considered.find(pi.name); w != rep.with_considered.end()) {
      label = "  (only with considered";
      for (const std::string& c : w->second) label += " " + c;
      label += " at nominal)";
    } else if (rep.not_estimable.count(pi.name)) {
      label = "  (not estimable on its own)";
    }
    std::printf("%-26s %16s %10s %10.5g  %s%s\n", pi.name.c_str(), v.value.c_str(),
                v.sigma.c_str(), r.initial.theta[i] / f, pi.unit.c_str(), label.c_str());
  }
  for (const WeakDirection& d : rep.weak) {
    std::printf("NOT SEPARABLE: %s (sigma %.0f%% of the prior along it)\n", d.description.c_str(),
                100.0 * d.sigma_ratio);
  }
}

std::string ResidualsCsv(const BatchResult& r) {
  std::ostringstream s;
  s << "# triadcal fit residuals per epoch: measurement m_* = x - B2 reference, process p_* of\n"
    << "# the interval ending at the epoch (0 at the first); v in m/s, s in m\n";
  s << "t,m_vx,m_vy,m_vz,m_sx,m_sy,m_sz,p_vx,p_vy,p_vz,p_sx,p_sy,p_sz\n";
  for (std::size_t e = 0; e < r.epoch_t.size(); ++e) {
    s << FormatDouble(r.epoch_t[e]);
    for (int c = 0; c < 6; ++c) s << "," << FormatDouble(r.measurement_residual[e][c]);
    for (int c = 0; c < 6; ++c) s << "," << FormatDouble(r.process_residual[e][c]);
    s << "\n";
  }
  return s.str();
}

}  // namespace triadcal
