// SHA-256 (FIPS 180-4) of bytes and of files, as lowercase hex: the input
// checksums of every output's provenance.
#pragma once

#include <string>

namespace triadcal {

// SHA-256 of the bytes of `data`, 64 lowercase hex digits.
std::string Sha256Hex(const std::string& data);

// SHA-256 of a file's contents, read in blocks; throws InputError
// ("PATH: cannot read ...") when the file cannot be read.
std::string Sha256OfFile(const std::string& path);

}  // namespace triadcal
