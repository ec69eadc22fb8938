#include "tools/report/value_format.h"

#include <gtest/gtest.h>

#include <cmath>

namespace triadcal {
namespace {

TEST(FormatWithSigma, ValueToTheSecondDigitOfSigma) {
  const ValueText t = FormatWithSigma(1504.201234, 0.009512);
  EXPECT_EQ(t.value, "1504.2012");
  EXPECT_EQ(t.sigma, "0.0095");
  EXPECT_EQ(ValuePlusMinus(1504.201234, 0.009512), "1504.2012 \xC2\xB1 0.0095");
}

TEST(FormatWithSigma, SigmaAboveOne) {
  EXPECT_EQ(ValuePlusMinus(171.52345, 1.234), "171.5 \xC2\xB1 1.2");
  EXPECT_EQ(ValuePlusMinus(-7.26, 3.08), "-7.3 \xC2\xB1 3.1");
  EXPECT_EQ(ValuePlusMinus(1234567.0, 2345.0), "1234600 \xC2\xB1 2300");
  EXPECT_EQ(ValuePlusMinus(12.0, 10.0), "12 \xC2\xB1 10");
}

TEST(FormatWithSigma, RoundingCarriesSigmaUpADecade) {
  // 0.0996 has two significant digits 0.10 once rounded: one decimal fewer.
  EXPECT_EQ(ValuePlusMinus(3.14159, 0.0996), "3.14 \xC2\xB1 0.10");
  EXPECT_EQ(ValuePlusMinus(3.14159, 0.0994), "3.142 \xC2\xB1 0.099");
}

TEST(FormatWithSigma, SmallValuesAndNegativeZero) {
  EXPECT_EQ(ValuePlusMinus(1.2e-3, 8.4e-4), "0.00120 \xC2\xB1 0.00084");
  EXPECT_EQ(ValuePlusMinus(-0.00001, 0.5), "0.00 \xC2\xB1 0.50");
  EXPECT_EQ(ValuePlusMinus(0.0, 0.021), "0.000 \xC2\xB1 0.021");
}

TEST(FormatWithSigma, ExtremeSigmaUsesExponent) {
  EXPECT_EQ(ValuePlusMinus(1.23456e-10, 2.3e-12), "1.235e-10 \xC2\xB1 2.3e-12");
  EXPECT_EQ(ValuePlusMinus(5.0e12, 4.4e10), "5.000e+12 \xC2\xB1 4.4e+10");
}

TEST(FormatWithSigma, NoSigma) {
  EXPECT_EQ(FormatWithSigma(171.523456, 0.0).value, "171.523");
  EXPECT_EQ(FormatWithSigma(171.523456, 0.0).sigma, "-");
  EXPECT_EQ(FormatWithSigma(2.0, std::nan("")).sigma, "-");
  EXPECT_EQ(FormatWithSigma(std::nan(""), 1.0).value, "nan");
}

}  // namespace
}  // namespace triadcal
