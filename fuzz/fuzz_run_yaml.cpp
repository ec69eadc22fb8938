// Fuzz target: run.yaml (bench, triad, constraints, columns, mounting, priors,
// data_format, positions) through the parser and the plausibility checks.
#include "core/io/run_description_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = triadcal_fuzz::WriteInput(data, size, "run.yaml");
  triadcal_fuzz::ExpectOnlyInputErrors([&] { triadcal::LoadRunDescription(path); });
  return 0;
}
