#pragma once
//! Internal to the I/O module: decimal text of a double that parses back to the same bits.
#include <charconv>
#include <string>

namespace mpm::io::detail {

//! 17 significant digits (printf's %.17g) always round-trip an IEEE double; NaN and infinities
//! come out as "nan", "inf", "-inf", which strtod reads back.
inline std::string to_text(double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::general, 17).ptr;
  return {buffer, end};
}

}  // namespace mpm::io::detail
