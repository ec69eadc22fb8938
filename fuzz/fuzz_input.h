// Shared by the fuzz targets: the input as a file (the readers take paths),
// and the rule that only triadcal's InputError may leave a reader; any other
// exception, a crash or a sanitizer report is a finding.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

#include "core/model/errors.h"

namespace triadcal_fuzz {

// Writes the input to a file of this process named `name` and returns its path.
inline std::string WriteInput(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const std::string path = "/tmp/triadcal_fuzz_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// Runs f(); an InputError is the expected answer to bad input.
template <typename F>
void ExpectOnlyInputErrors(F&& f) {
  try {
    f();
  } catch (const triadcal::InputError&) {
  }
}

}  // namespace triadcal_fuzz
