// SHA-256 (FIPS 180-4) through OpenSSL's libcrypto, which uses the CPU's SHA
// instructions where it has them (a 250-MB run file hashes in about 0.15 s
// instead of 0.9 s).
#include "core/io/sha256.h"

#include <openssl/evp.h>

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <vector>

#include "core/model/errors.h"

namespace triadcal {
namespace {

class Digest {
 public:
  Digest() : ctx_(EVP_MD_CTX_new(), &EVP_MD_CTX_free) {
    if (!ctx_ || EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr) != 1) {
      throw std::runtime_error("SHA-256: OpenSSL could not start a digest");
    }
  }
  void Update(const void* data, std::size_t n) {
    if (n > 0 && EVP_DigestUpdate(ctx_.get(), data, n) != 1) {
      throw std::runtime_error("SHA-256: OpenSSL digest update failed");
    }
  }
  std::string FinishHex() {
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    if (EVP_DigestFinal_ex(ctx_.get(), md, &len) != 1) {
      throw std::runtime_error("SHA-256: OpenSSL digest failed");
    }
    constexpr char kHex[] = "0123456789abcdef";
    std::string hex(2 * len, '0');
    for (unsigned int i = 0; i < len; ++i) {
      hex[2 * i] = kHex[md[i] >> 4];
      hex[2 * i + 1] = kHex[md[i] & 15];
    }
    return hex;
  }

 private:
  std::unique_ptr<EVP_MD_CTX, void (*)(EVP_MD_CTX*)> ctx_;
};

}  // namespace

std::string Sha256Hex(const std::string& data) {
  Digest d;
  d.Update(data.data(), data.size());
  return d.FinishHex();
}

std::string Sha256OfFile(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw InputError(path + ": cannot read (no such file or not readable)");
  Digest d;
  std::vector<char> buf(1 << 20);
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), f.get())) > 0) d.Update(buf.data(), n);
  if (std::ferror(f.get())) throw InputError(path + ": cannot read (I/O error)");
  return d.FinishHex();
}

}  // namespace triadcal
