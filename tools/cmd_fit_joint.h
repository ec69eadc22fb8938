// `triadcal fit` on several runs (tools/cmd_fit_joint.cpp).
#pragma once

#include <string>
#include <vector>

#include "app/fit_job.h"
#include "app/session.h"

namespace triadcal {

// Fits several runs of one IMU as one problem, writes out_json and prints
// the result; returns the exit status.
int RunJointFit(const FitSettings& settings, const std::vector<std::string>& inputs,
                const std::string& out_json, const std::string& report_html, Session& session);

}  // namespace triadcal
