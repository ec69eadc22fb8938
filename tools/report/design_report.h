// The tables `design` prints of its study (app/design_job.h, whose OUT the
// HTML report draws): sigma against duration, the profile grid, the targets,
// and the comparison with the static method.
#pragma once

#include <string>

#include "app/design_job.h"

namespace triadcal {

// The tables on stdout, up to the comparison's footnote.
void PrintDesign(const Scenario& s, const std::string& scenario_path,
                 const DesignSettings& settings, const DesignOutcome& o);

}  // namespace triadcal
