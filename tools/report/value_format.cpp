#include "tools/report/value_format.h"

#include <cmath>
#include <cstdio>

namespace triadcal {
namespace {

std::string Fixed(double x, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", decimals, x);
  std::string s = buf;
  // "-0.00" -> "0.00": a sign on a zero says nothing.
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

std::string Scientific(double x, int mantissa_decimals) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*e", mantissa_decimals, x);
  return buf;
}

}  // namespace

ValueText FormatWithSigma(double value, double sigma) {
  ValueText out;
  if (!std::isfinite(value)) {
    out.value = std::isnan(value) ? "nan" : (value > 0 ? "inf" : "-inf");
    out.sigma = std::isfinite(sigma) && sigma > 0 ? Scientific(sigma, 1) : "-";
    return out;
  }
  if (!(sigma > 0.0) || !std::isfinite(sigma)) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.6g", value);
    out.value = buf;
    out.sigma = "-";
    return out;
  }
  // Decimal exponent of sigma's leading digit; two significant digits end one
  // place below it. Rounding can carry sigma up a decade (0.0996 -> 0.100):
  // then one digit fewer.
  int lead = static_cast<int>(std::floor(std::log10(sigma)));
  double unit = std::pow(10.0, lead - 1);
  if (std::round(sigma / unit) >= 100.0) {
    ++lead;
    unit *= 10.0;
  }
  const int decimals = 1 - lead;
  if (decimals > 8 || lead > 9) {
    // Shared exponent: the value's mantissa carries digits down to sigma's
    // second significant digit.
    const int value_lead =
        value != 0.0 ? static_cast<int>(std::floor(std::log10(std::abs(value)))) : lead;
    out.value = Scientific(value, std::max(0, value_lead - lead + 1));
    out.sigma = Scientific(sigma, 1);
    return out;
  }
  if (decimals >= 0) {
    out.value = Fixed(value, decimals);
    out.sigma = Fixed(sigma, decimals);
  } else {
    out.value = Fixed(std::round(value / unit) * unit, 0);
    out.sigma = Fixed(std::round(sigma / unit) * unit, 0);
  }
  return out;
}

std::string ValuePlusMinus(double value, double sigma) {
  const ValueText t = FormatWithSigma(value, sigma);
  return t.value + " \xC2\xB1 " + t.sigma;
}

}  // namespace triadcal
