// Printing an estimate to the digit its uncertainty supports: sigma to two
// significant digits and the value to the same decimal place, e.g.
//   (1504.201234, 0.009512) -> "1504.2012" and "0.0095".
// One function so every printed table and the HTML report round alike.
#pragma once

#include <string>

namespace triadcal {

struct ValueText {
  std::string value, sigma;
};

// Rounds `value` to the decimal place of the second significant digit of
// `sigma`. When sigma is zero, negative or not finite the value is printed
// with 6 significant digits and sigma as "-". Very small or very large sigmas
// (beyond 1e-8 .. 1e9) use a shared exponent: "1.2345e-10", "2.3e-12".
ValueText FormatWithSigma(double value, double sigma);

// "1504.2012 ± 0.0095" (UTF-8 ±).
std::string ValuePlusMinus(double value, double sigma);

}  // namespace triadcal
