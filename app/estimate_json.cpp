#include "app/estimate_json.h"

#include <cmath>

namespace triadcal {

nlohmann::json ParametersJson(const ParameterLayout& layout, const Eigen::VectorXd& theta,
                              const Eigen::MatrixXd& cov,
                              const std::set<std::string>& not_estimable) {
  nlohmann::json out = nlohmann::json::object();
  for (int i = 0; i < layout.size(); ++i) {
    const ParameterInfo& info = layout.info(i);
    nlohmann::json p;
    p["value"] = theta[i] / info.si_per_unit;
    const bool estimable = not_estimable.count(info.name) == 0;
    // A held parameter has no sigma: it was not estimated (zero covariance).
    if (!estimable && cov(i, i) <= 0.0) {
      p["sigma"] = nullptr;
      p["held"] = true;
    } else {
      p["sigma"] = std::sqrt(std::max(0.0, cov(i, i))) / info.si_per_unit;
    }
    p["unit"] = info.unit;
    p["estimable"] = estimable;
    out[info.name] = p;
  }
  return out;
}

void MarkRelative(const std::map<std::string, std::vector<std::string>>& relative_to,
                  nlohmann::json* parameters) {
  for (const auto& [name, anchors] : relative_to) {
    if (!parameters->contains(name)) continue;
    (*parameters)[name]["relative_to"] = anchors;
    (*parameters)[name]["estimable"] = false;
  }
}

nlohmann::json WeakDirectionsJson(const std::vector<WeakDirection>& dirs) {
  nlohmann::json out = nlohmann::json::array();
  for (const WeakDirection& d : dirs) {
    nlohmann::json j;
    nlohmann::json w = nlohmann::json::object();
    for (const auto& [name, weight] : d.weights) w[name] = weight;
    j["parameters"] = w;
    j["description"] = d.description;
    j["sigma_ratio_to_prior"] = d.sigma_ratio;
    j["data_information"] = d.data_information;
    out.push_back(j);
  }
  return out;
}

nlohmann::json CorrelationJson(const ParameterLayout& layout, const Eigen::MatrixXd& cov) {
  nlohmann::json names = nlohmann::json::array();
  for (int i = 0; i < layout.size(); ++i) names.push_back(layout.info(i).name);
  nlohmann::json m = nlohmann::json::array();
  for (int r = 0; r < layout.size(); ++r) {
    nlohmann::json row = nlohmann::json::array();
    for (int c = 0; c < layout.size(); ++c) {
      const double d = std::sqrt(cov(r, r) * cov(c, c));
      row.push_back(d > 0 ? cov(r, c) / d : 0.0);
    }
    m.push_back(row);
  }
  return {{"names", names}, {"matrix", m}};
}

}  // namespace triadcal
