// Fuzz target: a calibration file (OUT of fit, static, filter, compare, or a
// truth.json) through LoadCalibration.
#include "core/io/calibration_io.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = triadcal_fuzz::WriteInput(data, size, "cal.json");
  triadcal_fuzz::ExpectOnlyInputErrors([&] { triadcal::LoadCalibration(path); });
  return 0;
}
