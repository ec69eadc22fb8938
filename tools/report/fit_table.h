// What `fit` prints of a batch solution (its OUT is app/fit_report.h's): the
// parameter table, and the residuals per epoch of --residuals.
#pragma once

#include <string>

#include "app/fit_report.h"

namespace triadcal {

void PrintParameterTable(const ParameterLayout& layout, const BatchResult& r, const FitReport& rep);
std::string ResidualsCsv(const BatchResult& r);

}  // namespace triadcal
