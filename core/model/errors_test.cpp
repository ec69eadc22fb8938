// One-line error text: control characters escaped, and at most a short
// excerpt of any text read from an input.
#include "core/model/errors.h"

#include <gtest/gtest.h>

#include <string>

namespace triadcal {
namespace {

TEST(Errors, OneLineEscapesControlCharacters) {
  EXPECT_EQ(OneLine("a\nb\tc\x1b[2J\x7f"), "a\\nb\\tc\\x1B[2J\\x7F");
}

TEST(Errors, ExcerptKeepsShortTextAndCutsLongText) {
  EXPECT_EQ(Excerpt("wx"), "wx");
  EXPECT_EQ(Excerpt(std::string(60, 'a')), std::string(60, 'a'));
  const std::string long_text = std::string(1000000, 'a') + "0123456789AB";
  const std::string e = Excerpt(long_text);
  EXPECT_EQ(e, std::string(40, 'a') + "..." + "0123456789AB");
  EXPECT_LE(e.size(), 60u);
  // Escaped bytes count: 1000 NULs stay within the bound too.
  const std::string nuls = Excerpt(std::string(1000, '\0'), 40);
  EXPECT_LE(nuls.size(), 40u);
  EXPECT_EQ(nuls.find('\0'), std::string::npos);
  EXPECT_EQ(nuls.rfind("\\x00", 0), 0u);
  // A short text that escapes long is cut as well.
  EXPECT_LE(Excerpt(std::string(50, '\x01'), 60).size(), 60u);
}

}  // namespace
}  // namespace triadcal
