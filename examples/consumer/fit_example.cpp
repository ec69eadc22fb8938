// fit_example RUN.yaml: the batch fit of `triadcal fit RUN.yaml` through the
// library; prints {"NAME": {"value": v, "sigma": s, "unit": u}, ...} in the
// units of the OUT files.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include <triadcal/core/io/run_description_io.h>
#include <triadcal/core/io/run_io.h>
#include <triadcal/core/model/errors.h>
#include <triadcal/core/model/parameters.h>
#include <triadcal/solvers/estimation/batch_solver.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fit_example RUN.yaml\n");
    return 2;
  }
  try {
    const triadcal::RunDescription run = triadcal::LoadRunDescription(argv[1]);
    const triadcal::RunData data = triadcal::LoadRunData(run, nullptr);
    const triadcal::ParameterLayout layout;  // the 27 base parameters
    triadcal::BatchOptions options;          // as `triadcal fit` sets them by default
    options.epoch_s = 0.5;
    options.derivatives.half_window_s = 0.1;
    const triadcal::BatchResult r = triadcal::SolveBatch(run, data, layout, options);

    nlohmann::ordered_json out;
    for (int i = 0; i < layout.size(); ++i) {
      const triadcal::ParameterInfo& info = layout.info(i);
      out[info.name] = {
          {"value", r.estimate.theta[i] / info.si_per_unit},
          {"sigma", std::sqrt(std::max(0.0, r.estimate.cov(i, i))) / info.si_per_unit},
          {"unit", info.unit}};
    }
    std::cout << out.dump(2) << "\n";
  } catch (const triadcal::InputError& e) {
    std::fprintf(stderr, "fit_example: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
