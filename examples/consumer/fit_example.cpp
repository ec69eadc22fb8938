// fit_example RUN.yaml: `triadcal fit RUN.yaml` through the library, by the
// very job the command runs (app/fit_job.h); prints {"NAME": {"value": v,
// "sigma": s, "unit": u}, ...} from its OUT, in the units of the OUT files.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>

#include <triadcal/app/fit_job.h>
#include <triadcal/app/run_loading.h>
#include <triadcal/app/session.h>
#include <triadcal/core/model/errors.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fit_example RUN.yaml\n");
    return 2;
  }
  try {
    triadcal::Session session;  // no progress, no provenance of a binary
    const triadcal::LoadedRun run = triadcal::LoadRun(argv[1], &session);
    const triadcal::FitSettings settings;  // the defaults of `triadcal fit`
    const triadcal::FitOutcome fit = triadcal::FitRun(settings, argv[1], run, session);

    nlohmann::ordered_json out;
    for (const auto& [name, p] : fit.json["parameters"].items()) {
      out[name] = {{"value", p["value"]}, {"sigma", p["sigma"]}, {"unit", p["unit"]}};
    }
    std::cout << out.dump(2) << "\n";
  } catch (const triadcal::InputError& e) {
    std::fprintf(stderr, "fit_example: error: %s\n", e.what());
    return 2;
  }
  return 0;
}
