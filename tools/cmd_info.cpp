// `triadcal params`: the parameter names, units and effects that files use.
#include <cstdio>
#include <string>

#include "core/model/effects.h"
#include "core/model/parameters.h"
#include "tools/commands.h"

namespace triadcal {

Command AddInfoCommand(CLI::App& app) {
  Command c;
  c.app = app.add_subcommand("params", "List parameter names and units, and the effect catalogue");
  c.run = [](Session&) {
    std::printf("Base parameters (docs/file-formats.md):\n");
    for (const ParameterInfo& p : BaseParameterInfo()) {
      std::printf("  %-10s %s\n", p.name.c_str(), p.unit.c_str());
    }
    std::printf("\nGyro parameters (with a gyro block in run.yaml; docs/file-formats.md):\n");
    for (const ParameterInfo& p : GyroParameterInfo()) {
      std::printf("  %-13s %s\n", p.name.c_str(), p.unit.c_str());
    }
    std::printf("\nEffects (docs/method.md), parameters named effect.param:\n");
    for (const EffectSpec& e : EffectCatalogue()) {
      std::printf("  %-26s %s\n", e.name.c_str(), e.description.c_str());
      std::string needs;
      if (e.needs.temp_C) needs += ", needs temp_C";
      if (e.needs.rates_at_every_sample) needs += ", needs rates at every sample";
      std::printf("      stage %s%s; B1 Jacobian %s\n", StageName(e.stage), needs.c_str(),
                  e.b1_analytic_jacobian ? "analytic" : "by Jets");
      for (const ParamSpec& p : e.params) {
        // Sizes relative to the nominal scale factor print as percentages.
        const double f = e.scale_relative ? 100.0 : 1.0;
        const char* rel = e.scale_relative ? " % of K" : "";
        std::printf("      %-10s %-8s (scenario key %s)  prior sigma %g%s, plausible %g .. %g%s\n",
                    p.name.c_str(), p.unit.c_str(), UnitSuffixedKey(p).c_str(), f * p.prior_sigma,
                    rel, f * p.plausible_min, f * p.plausible_max, rel);
      }
      std::printf("      plausible range: %s\n", e.plausible_reason.c_str());
    }
    return 0;
  };
  return c;
}

}  // namespace triadcal
