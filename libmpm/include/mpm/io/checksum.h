#pragma once
//! A 64-bit content checksum for detecting files changed after they were written (a corrupted or
//! edited checkpoint, an input mesh edited between a run and its restart). Not cryptographic: it
//! guards against accidents, not against forgery. Words of 8 bytes are mixed with a multiply-xorshift
//! step (the finaliser of MurmurHash3), so one changed bit anywhere changes the result.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

namespace mpm::io {

class Checksum {
public:
  void add(const void* data, std::size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= bytes; i += 8) {
      std::uint64_t word;
      std::memcpy(&word, p + i, 8);
      mix(word);
    }
    std::uint64_t tail = 0;
    if (i < bytes) std::memcpy(&tail, p + i, bytes - i);   // no memcpy from the null data of an empty vector
    mix(tail ^ (static_cast<std::uint64_t>(bytes) << 3));  // the length separates "ab" + "c" from "a" + "bc"
  }
  void add(std::string_view text) { add(text.data(), text.size()); }

  std::uint64_t value() const { return h_; }
  //! 16 hex digits.
  std::string hex() const { return hex(h_); }
  static std::string hex(std::uint64_t value) {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
    return text;
  }

private:
  void mix(std::uint64_t word) {
    h_ = (h_ ^ word) * 0xff51afd7ed558ccdull;
    h_ ^= h_ >> 33;
    h_ *= 0xc4ceb9fe1a85ec53ull;
    h_ ^= h_ >> 29;
  }
  std::uint64_t h_ = 0x9e3779b97f4a7c15ull;
};

}  // namespace mpm::io
