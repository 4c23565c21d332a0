#pragma once
//! Numbers in error messages, in the shortest %g form ("1e-05", "0.6"), not std::to_string's
//! fixed six decimals ("0.000010").
#include <charconv>
#include <sstream>
#include <string>

namespace mpm {

inline std::string number_text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

//! The shortest text that reads back to the same double ("0.0075", "1e-05", "90"): numbers
//! written to be read again (override values, CSV files).
inline std::string exact_number_text(double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  return {buffer, end};
}

}  // namespace mpm
