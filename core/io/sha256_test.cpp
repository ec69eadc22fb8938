// SHA-256 against the FIPS 180-4 / NIST example vectors and sha256sum.
#include "core/io/sha256.h"

#include <gtest/gtest.h>

#include <string>

#include "core/model/errors.h"
#include "tests/temp_dir_test.h"

namespace triadcal {
namespace {

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // 448 bits: the padding spills into a second block.
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex("abcdefghbcdefghicdefghijdefghijkefghijklfghijklmghijklmn"
                      "hijklmnoijklmnopjklmnopqklmnopqrlmnopqrsmnopqrstnopqrstu"),
            "cf5b16a778af8380036ce59e7b0492370b249b11e8f07a51afac45037afee9d1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// Every padding length around the block boundary (55, 56, 63, 64 bytes) gives
// what sha256sum gives.
TEST(Sha256, BlockBoundaries) {
  EXPECT_EQ(Sha256Hex(std::string(55, 'x')),
            "d5e285683cd4efc02d021a5c62014694958901005d6f71e89e0989fac77e4072");
  EXPECT_EQ(Sha256Hex(std::string(56, 'x')),
            "04c26261370ee7541549d16dee320c723e3fd14671e66a099afe0a377c16888e");
  EXPECT_EQ(Sha256Hex(std::string(63, 'x')),
            "75220b47218278e656f2013bb8f0c455a25eaf01e86c64924e9d48d89776d6f2");
  EXPECT_EQ(Sha256Hex(std::string(64, 'x')),
            "7ce100971f64e7001e8fe5a51973ecdfe1ced42befe7ee8d5fd6219506b5393c");
}

class Sha256File : public testing_fixtures::TempDirTest {};

TEST_F(Sha256File, FileEqualsBytes) {
  std::string text;
  for (int i = 0; i < 200000; ++i) text += static_cast<char>(i * 7 % 251);
  const std::string path = WriteText("data.bin", text);
  EXPECT_EQ(Sha256OfFile(path), Sha256Hex(text));
}

TEST_F(Sha256File, MissingFile) {
  try {
    Sha256OfFile(Path("absent.csv"));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("absent.csv") + ": cannot read (no such file or not readable)");
  }
}

}  // namespace
}  // namespace triadcal
