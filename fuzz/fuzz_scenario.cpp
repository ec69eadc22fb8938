// Fuzz target: the scenario file of `simulate` (profile, truth, noise,
// effects, run) through its parser.
#include "core/simulation/simulator.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = triadcal_fuzz::WriteInput(data, size, "scenario.yaml");
  triadcal_fuzz::ExpectOnlyInputErrors([&] { triadcal::LoadScenario(path); });
  return 0;
}
