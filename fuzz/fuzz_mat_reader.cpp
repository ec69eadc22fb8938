// Fuzz target: a MATLAB v5 data file through the whole loading path: the
// element walker (tags, dimensions, data types, compressed elements), matio,
// the column mapping, validation and plausibility.
#include "core/io/run_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = triadcal_fuzz::WriteInput(data, size, "run.mat");
  triadcal_fuzz::ExpectOnlyInputErrors([&] {
    triadcal::RunDescription run;
    run.yaml_path = "run.yaml";
    run.data_path = path;
    triadcal::RunWarnings warnings;
    triadcal::LoadRunData(run, &warnings);
  });
  return 0;
}
