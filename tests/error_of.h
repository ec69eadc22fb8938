// The one-line message of the InputError a call throws, for tests of bad
// input and bad settings.
#pragma once

#include <string>
#include <utility>

#include "core/model/errors.h"

namespace triadcal {
namespace testing_fixtures {

// What f() throws as an InputError; "" when it throws nothing.
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    std::forward<F>(f)();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// What a job's settings' Validate() says of them; "" when they are valid.
template <typename Settings>
std::string ValidateError(const Settings& s) {
  return ErrorOf([&] { s.Validate(); });
}

}  // namespace testing_fixtures
}  // namespace triadcal
