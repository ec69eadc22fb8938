#include "tools/report/observability_report.h"

#include <cmath>
#include <cstdio>
#include <set>

#include "app/estimate_json.h"

namespace triadcal {
namespace {

std::string Fmt(double x) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.3g", x);
  return b;
}

std::set<std::string> UnobservableNames(const ObservabilityVariant& v) {
  std::vector<WeakDirection> dirs;
  for (const Direction& d : v.unobservable) dirs.push_back(d.named);
  const std::vector<std::string> names = ParametersIn(dirs);
  return {names.begin(), names.end()};
}

}  // namespace

nlohmann::json DirectionJson(const ParameterLayout& layout, const Direction& d) {
  nlohmann::json j = WeakDirectionsJson({d.named})[0];
  if (d.data_sigma.size() > 0) {
    nlohmann::json s = nlohmann::json::object();
    for (const auto& [name, w] : d.named.weights) {
      const int i = layout.IndexOf(name);
      s[name] = d.data_sigma[i] / layout.info(i).si_per_unit;
    }
    j["data_sigma"] = s;
  }
  return j;
}

nlohmann::json VariantJson(const ParameterLayout& layout, const ObservabilityVariant& v) {
  nlohmann::json j;
  j["constraints"] = v.constraints;
  nlohmann::json crb = nlohmann::json::object();
  for (int i = 0; i < layout.size(); ++i) {
    crb[layout.info(i).name] = std::sqrt(std::max(0.0, v.cov(i, i))) / layout.info(i).si_per_unit;
  }
  j["crb"] = crb;
  j["unobservable"] = nlohmann::json::array();
  for (const Direction& d : v.unobservable) j["unobservable"].push_back(DirectionJson(layout, d));
  j["weakly_observable"] = nlohmann::json::array();
  for (const Direction& d : v.weak) j["weakly_observable"].push_back(DirectionJson(layout, d));
  const std::set<std::string> held = UnobservableNames(v);
  j["not_estimable"] = std::vector<std::string>(held.begin(), held.end());
  j["information_eigenvalues_prior_units"] =
      std::vector<double>(v.eigenvalues.data(), v.eigenvalues.data() + v.eigenvalues.size());
  return j;
}

nlohmann::json ObservabilityJson(const ObservabilityResult& r) {
  const ParameterLayout& L = r.layout;
  nlohmann::json out;
  const nlohmann::json with = VariantJson(L, r.with_constraints);
  out["crb"] = with["crb"];
  nlohmann::json units = nlohmann::json::object();
  for (int i = 0; i < L.size(); ++i) units[L.info(i).name] = L.info(i).unit;
  out["units"] = units;
  out["constraints"] = r.with_constraints.constraints;
  out["unobservable"] = with["unobservable"];
  out["weakly_observable"] = with["weakly_observable"];
  out["not_estimable"] = with["not_estimable"];
  out["correlation"] = CorrelationJson(L, r.with_constraints.cov);
  const std::set<std::string> held = UnobservableNames(r.with_constraints);
  // the OUT form of docs/file-formats.md: value = the point of evaluation, sigma = the CRB.
  out["parameters"] = ParametersJson(L, r.theta, r.with_constraints.cov, held);
  nlohmann::json prior = nlohmann::json::object();
  for (int i = 0; i < L.size(); ++i) prior[L.info(i).name] = r.prior.sigma[i] / L.info(i).si_per_unit;
  out["prior_sigma"] = prior;
  out["with_constraints"] = with;
  out["without_constraints"] = VariantJson(L, r.without_constraints);
  nlohmann::json each = nlohmann::json::object();
  for (std::size_t j = 0; j < r.without_each.size(); ++j) {
    each[r.without_each[j].dropped] = VariantJson(L, r.without_each[j]);  // key: the one dropped
  }
  out["without_each_constraint"] = each;
  out["run"] = {{"samples", r.samples}, {"epochs", r.epochs}, {"duration_s", r.duration_s}};
  out["time_s"] = r.seconds;
  return out;
}

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
