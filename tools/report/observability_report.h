// What `observability` prints about an observability analysis
// (solvers/estimation/observability.h): the CRB per parameter and the
// unobservable and weakly observable directions of each set of constraints.
// Its OUT is the job's (app/observability_job.h).
#pragma once

#include <string>

#include "solvers/estimation/observability.h"

namespace triadcal {

// The table and the direction lines on stdout.
void PrintObservability(const ObservabilityResult& r);

// One line per direction: "UNOBSERVABLE: sentence [name weight, ...]".
std::string DirectionLine(const ParameterLayout& layout, const Direction& d, bool observable);

}  // namespace triadcal
