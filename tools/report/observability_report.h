// What `observability` (and `design`) write and print about an observability
// analysis (solvers/estimation/observability.h): the CRB per parameter, the correlation
// matrix, and the unobservable and weakly observable directions of each set of
// constraints.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "solvers/estimation/observability.h"

namespace triadcal {

// {"parameters": {name: weight}, "description", "data_information",
//  "sigma_ratio_to_prior"} and, for an observable direction, "data_sigma":
// {name: sigma in file units along it, data and constraints alone}.
nlohmann::json DirectionJson(const ParameterLayout& layout, const Direction& d);

// {"constraints": [...], "crb": {name: sigma}, "unobservable": [...],
//  "weakly_observable": [...], "information_eigenvalues_prior_units": [...]}
nlohmann::json VariantJson(const ParameterLayout& layout, const ObservabilityVariant& v);

// The whole OUT of `observability` (without the command's own settings).
nlohmann::json ObservabilityJson(const ObservabilityResult& r);

// The table and the direction lines on stdout.
void PrintObservability(const ObservabilityResult& r);

// One line per direction: "UNOBSERVABLE: sentence [name weight, ...]".
std::string DirectionLine(const ParameterLayout& layout, const Direction& d, bool observable);

}  // namespace triadcal
