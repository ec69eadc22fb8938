// `triadcal params`: the parameter names, units and effects that files use.
#include <cstdio>

#include "core/model/effects.h"
#include "core/model/parameters.h"
#include "tools/commands.h"

namespace triadcal {

Command AddInfoCommand(CLI::App& app) {
  Command c;
  c.app = app.add_subcommand("params", "List parameter names and units, and the effect catalogue");
  c.run = [] {
    std::printf("Base parameters (docs/file-formats.md):\n");
    for (const ParameterInfo& p : BaseParameterInfo()) {
      std::printf("  %-10s %s\n", p.name.c_str(), p.unit.c_str());
    }
    std::printf("\nEffects (docs/method.md), parameters named effect.param:\n");
    for (const EffectSpec& e : EffectCatalogue()) {
      std::printf("  %-26s %s\n", e.name.c_str(), e.description.c_str());
      for (const ParamSpec& p : e.params) {
        std::printf("      %-10s %-8s (scenario key %s)\n", p.name.c_str(), p.unit.c_str(),
                    UnitSuffixedKey(p).c_str());
      }
    }
    return 0;
  };
  return c;
}

}  // namespace triadcal
