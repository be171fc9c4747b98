// SHA-256 (FIPS 180-4) of a file's bytes: how a recording names the model files it came
// from, so that `sha256sum` on another machine tells whether a file is the same one.
#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace afhub::mcap {

// The digest as 64 lowercase hex digits, as sha256sum prints it.
std::string sha256_hex(std::span<const std::uint8_t> bytes);

}  // namespace afhub::mcap
