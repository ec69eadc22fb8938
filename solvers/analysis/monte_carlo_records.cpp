#include "solvers/analysis/monte_carlo_records.h"

#include <cmath>
#include <limits>

#include "core/model/errors.h"

namespace triadcal {

nlohmann::json ExactJson(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  return x;
}

nlohmann::json ExactJson(const Eigen::VectorXd& v) {
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) a.push_back(ExactJson(v[i]));
  return a;
}

namespace {

double ExactDouble(const nlohmann::json& j, const std::string& where) {
  if (j.is_number()) return j.get<double>();
  if (j == "nan") return std::numeric_limits<double>::quiet_NaN();
  if (j == "inf") return std::numeric_limits<double>::infinity();
  if (j == "-inf") return -std::numeric_limits<double>::infinity();
  throw InputError(where + ": expected a number, \"nan\", \"inf\" or \"-inf\", got " + j.dump());
}

}  // namespace

Eigen::VectorXd ExactVector(const nlohmann::json& j, int size, const std::string& where) {
  if (!j.is_array() || static_cast<int>(j.size()) != size) {
    throw InputError(where + ": expected a list of " + std::to_string(size) + " numbers");
  }
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) v[i] = ExactDouble(j[i], where);
  return v;
}

nlohmann::json MonteCarloRunsJson(const std::vector<MonteCarloRun>& runs) {
  nlohmann::json out = nlohmann::json::array();
  for (const MonteCarloRun& r : runs) {
    nlohmann::json est = nlohmann::json::array();
    for (std::size_t j = 0; j < r.error.size(); ++j) {
      est.push_back({{"error", ExactJson(r.error[j])},
                     {"sigma", ExactJson(r.sigma[j])},
                     {"failure", j < r.failure.size() ? r.failure[j] : std::string()}});
    }
    out.push_back({{"seed", r.seed}, {"truth", ExactJson(r.truth)}, {"estimators", est}});
  }
  return out;
}

std::vector<MonteCarloRun> MonteCarloRunsFromJson(const nlohmann::json& j, std::size_t estimators,
                                                  int parameters, const std::string& where) {
  const std::string at = where + ": records";
  if (!j.is_array()) throw InputError(at + ": expected a list of runs");
  std::vector<MonteCarloRun> runs;
  for (std::size_t k = 0; k < j.size(); ++k) {
    const nlohmann::json& jr = j[k];
    const std::string here = at + "[" + std::to_string(k) + "]";
    if (!jr.is_object() || !jr.contains("seed") || !jr["seed"].is_number_unsigned() ||
        !jr.contains("estimators") || !jr["estimators"].is_array() ||
        jr["estimators"].size() != estimators || !jr.contains("truth")) {
      throw InputError(here + ": expected {seed, truth, estimators} with " +
                       std::to_string(estimators) + " estimators");
    }
    MonteCarloRun r;
    r.seed = jr["seed"].get<std::uint64_t>();
    r.truth = ExactVector(jr["truth"], parameters, here + ".truth");
    for (const nlohmann::json& e : jr["estimators"]) {
      if (!e.is_object() || !e.contains("error") || !e.contains("sigma") ||
          !e.contains("failure") || !e["failure"].is_string()) {
        throw InputError(here + ".estimators: expected {error, sigma, failure}");
      }
      const bool failed = e["error"].is_array() && e["error"].empty();
      const int size = failed ? 0 : parameters;
      r.error.push_back(ExactVector(e["error"], size, here + ".error"));
      r.sigma.push_back(ExactVector(e["sigma"], size, here + ".sigma"));
      r.failure.push_back(e["failure"].get<std::string>());
    }
    runs.push_back(std::move(r));
  }
  return runs;
}

}  // namespace triadcal
