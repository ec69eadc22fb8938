#include "tools/report/design_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/io/file_util.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

std::string PairText(double a, double b) {
  char t[48];
  std::snprintf(t, sizeof(t), "%g:%g", a, b);
  return t;
}

// Widths of the name and unit columns: the longest of each (gyro.alpha_x,
// (deg/s)/g).
struct Widths {
  int name = 9, unit = 7;
  explicit Widths(const ParameterLayout& layout) {
    for (int i = 0; i < layout.size(); ++i) {
      name = std::max(name, static_cast<int>(layout.info(i).name.size()));
      unit = std::max(unit, static_cast<int>(layout.info(i).unit.size()));
    }
  }
  void Print(const std::string& a, const std::string& b) const {
    std::printf("%-*s %-*s", name, a.c_str(), unit, b.c_str());
  }
};

void PrintDurationTable(const ParameterLayout& layout, const DesignStudy& r, const char* what,
                        const std::vector<DesignPoint>& pts) {
  std::printf("\n%s: sigma against run duration [s] (* not determined: the prior's)\n", what);
  const Widths w(layout);
  w.Print("parameter", "unit");
  for (double T : r.durations_s) std::printf(" %9g", T);
  std::printf(" %7s\n", "slope");
  for (int i = 0; i < layout.size(); ++i) {
    const double f = layout.info(i).si_per_unit;
    w.Print(layout.info(i).name, layout.info(i).unit);
    std::vector<double> v;
    for (const DesignPoint& d : pts) {
      const bool held = Undetermined(d, layout.info(i).name);
      std::printf(" %8.3g%s", d.sigma[i] / f, held ? "*" : " ");
      v.push_back(held ? std::nan("") : d.sigma[i] / f);
    }
    const double slope = LogSlope(r.durations_s, v, 60.0);
    if (std::isfinite(slope)) {
      std::printf(" %7.3f\n", slope);
    } else {
      std::printf(" %7s\n", "-");
    }
  }
}

void PrintGrid(const ParameterLayout& layout, const DesignStudy& r) {
  std::printf("\nprofiles at %g s: worst sigma per group (* not determined)\n",
              r.design_duration_s);
  std::printf("%-12s %-12s", "periods s", "ampl. deg");
  for (const ParameterGroup& g : ParameterGroups()) std::printf(" %10s", g.name.c_str());
  std::printf("  unobservable\n");
  for (const DesignGridPoint& g : r.grid) {
    std::printf("%-12s %-12s", PairText(g.period_s[0], g.period_s[1]).c_str(),
                PairText(g.amplitude_deg[0], g.amplitude_deg[1]).c_str());
    for (const ParameterGroup& grp : ParameterGroups()) {
      std::printf(" %9.3g%s",
                  WorstSigma(g.d, grp.members) / layout.info(grp.members[0]).si_per_unit,
                  AnyUndetermined(g.d, layout, grp.members) ? "*" : " ");
    }
    std::string held;
    for (const std::string& h : g.d.unobservable) held += (held.empty() ? "" : " ") + h;
    std::printf("  %s\n", held.empty() ? "-" : held.c_str());
  }
}

void PrintTargets(const ParameterLayout& layout, const DesignStudyOptions& o,
                  const DesignStudy& r) {
  std::printf("\n");
  for (std::size_t k = 0; k < o.targets.size(); ++k) {
    const DesignTarget& t = o.targets[k];
    const TargetResult& tr = r.targets[k];
    const std::string unit = layout.info(t.indices[0]).unit;
    if (tr.reached) {
      std::printf(
          "target sigma(%s) <= %g %s: reached after %.3g s of the profile (sigma %.3g; %d CRB "
          "evaluations)\n",
          t.key.c_str(), t.sigma_file, unit.c_str(), tr.duration_s,
          tr.sigma_at_duration / layout.info(t.indices[0]).si_per_unit, tr.evaluations);
    } else {
      std::printf("target sigma(%s) <= %g %s: NOT reached within %g s (sigma %.3g there)\n",
                  t.key.c_str(), t.sigma_file, unit.c_str(), tr.duration_s,
                  tr.sigma_at_duration / layout.info(t.indices[0]).si_per_unit);
    }
  }
}

void PrintComparison(const ParameterLayout& layout, const DesignStudy& r,
                     const DesignSettings& settings) {
  const double Td = r.design_duration_s, Ts = r.static_duration_s;
  std::printf(
      "\nquasi-harmonic %g s against the static %d-position method, %g s (* not determined)\n", Td,
      settings.static_positions, Ts);
  const Widths w(layout);
  w.Print("parameter", "unit");
  std::printf(" %14s %14s %14s %10s\n", "quasi-harm.", "static", "static same T", "ratio");
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& p = layout.info(i);
    const double f = p.si_per_unit;
    auto held = [&](const DesignPoint& d) { return Undetermined(d, p.name) ? "*" : " "; };
    char ratio[32];
    if (Undetermined(r.static_long, p.name) || Undetermined(r.qh_design, p.name)) {
      std::snprintf(ratio, sizeof(ratio), "%10s", "-");
    } else {
      std::snprintf(ratio, sizeof(ratio), "%10.3g", r.static_long.sigma[i] / r.qh_design.sigma[i]);
    }
    w.Print(p.name, p.unit);
    std::printf(" %13.3g%s %13.3g%s %13.3g%s %s\n", r.qh_design.sigma[i] / f, held(r.qh_design), r.static_long.sigma[i] / f,
                held(r.static_long), r.static_design.sigma[i] / f, held(r.static_design), ratio);
  }
  std::printf(
      "(ratio: static %g s sigma / quasi-harmonic %g s sigma; -: not determined by one of them)\n",
      Ts, Td);
  if (layout.has_gyro()) {
    std::printf(
        "(the static method here is the accelerometer's: the gyro's parameters show their "
        "priors there)\n");
  }
}

}  // namespace

void PrintDesign(const Scenario& s, const std::string& scenario_path,
                 const DesignSettings& settings, const DesignOutcome& o) {
  const ParameterLayout& layout = o.layout;
  const DesignStudyOptions& options = o.options;
  const DesignStudy& r = o.study;
  std::string gyro;
  if (s.run.gyro) {
    char t[64];
    std::snprintf(t, sizeof(t), ", gyro %g deg/s", s.run.gyro->noise_rad_s.maxCoeff() / kDegToRad);
    gyro = t;
  }
  std::printf("design: %s, %g Hz, declared noise %g %s, %g arcsec%s; static test: %d positions\n",
              scenario_path.c_str(), s.profile.rate_hz, s.run.noise_mV,
              layout.readings_unit().c_str(), s.run.angle_noise_rad / kArcsecToRad, gyro.c_str(),
              settings.static_positions);
  PrintDurationTable(layout, r, "quasi-harmonic profile", r.quasi_harmonic);
  PrintDurationTable(layout, r, "static multi-position test", r.static_test);
  std::printf("(slope: log-log over durations >= 60 s; -0.5 is 1/sqrt(T))\n");
  PrintGrid(layout, r);
  PrintTargets(layout, options, r);
  PrintComparison(layout, r, settings);
}

}  // namespace triadcal
