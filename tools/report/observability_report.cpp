#include "tools/report/observability_report.h"

#include <cmath>
#include <cstdio>
#include <set>

#include "app/observability_job.h"

namespace triadcal {
namespace {

std::string Fmt(double x) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.3g", x);
  return b;
}

}  // namespace

std::string DirectionLine(const ParameterLayout& layout, const Direction& d, bool observable) {
  std::string s = observable ? "weakly observable: " : "UNOBSERVABLE: ";
  s += d.named.description;
  s += " [";
  for (std::size_t k = 0; k < d.named.weights.size(); ++k) {
    const auto& [name, w] = d.named.weights[k];
    s += (k ? ", " : "") + name + " " + Fmt(w);
  }
  s += "]";
  if (observable) {
    s += "; the data give sigma";
    for (std::size_t k = 0; k < d.named.weights.size(); ++k) {
      const int i = layout.IndexOf(d.named.weights[k].first);
      s += (k ? ", " : " ") + Fmt(d.data_sigma[i] / layout.info(i).si_per_unit) + " " +
           layout.info(i).unit + " " + d.named.weights[k].first;
    }
    s += " along it (information " + Fmt(d.named.data_information) + " x the prior's)";
  } else {
    s += "; information " + Fmt(d.named.data_information) +
         " x the prior's: the estimate along it is the prior";
  }
  return s;
}

void PrintObservability(const ObservabilityResult& r) {
  const ParameterLayout& L = r.layout;
  const std::set<std::string> held = UnobservableNames(r.with_constraints);
  const std::set<std::string> held0 = UnobservableNames(r.without_constraints);
  std::printf("%-26s %-7s %12s %12s %14s %12s\n", "parameter", "unit", "at", "CRB sigma",
              "no constraints", "prior sigma");
  for (int i = 0; i < L.size(); ++i) {
    const ParameterInfo& p = L.info(i);
    const double f = p.si_per_unit;
    std::printf("%-26s %-7s %12.6g %11.3g%s %13.3g%s %12.3g\n", p.name.c_str(), p.unit.c_str(),
                r.theta[i] / f, std::sqrt(r.with_constraints.cov(i, i)) / f,
                held.count(p.name) ? "*" : " ", std::sqrt(r.without_constraints.cov(i, i)) / f,
                held0.count(p.name) ? "*" : " ", r.prior.sigma[i] / f);
  }
  std::printf("(* in an unobservable direction: the value is the prior's)\n");
  auto report = [&](const ObservabilityVariant& v) {
    std::string cons;
    for (const std::string& c : v.constraints) cons += (cons.empty() ? "" : ", ") + c;
    std::printf("%s%s%s%s:", v.name.c_str(), cons.empty() ? "" : " (", cons.c_str(),
                cons.empty() ? "" : ")");
    if (v.unobservable.empty() && v.weak.empty()) {
      std::printf(" every direction observable\n");
      return;
    }
    std::printf("%s\n", v.unobservable.empty() ? " nothing unobservable" : "");
    for (const Direction& d : v.unobservable) std::printf("  %s\n", DirectionLine(L, d, false).c_str());
    for (const Direction& d : v.weak) std::printf("  %s\n", DirectionLine(L, d, true).c_str());
  };
  if (r.with_constraints.constraints.empty()) {
    std::printf("(the run declares no constraints)\n");
    report(r.without_constraints);
    return;
  }
  report(r.with_constraints);
  report(r.without_constraints);
  // With one constraint, "without it" is "without constraints".
  if (r.without_each.size() > 1) {
    for (const ObservabilityVariant& v : r.without_each) report(v);
  }
}

}  // namespace triadcal
