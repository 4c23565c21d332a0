#pragma once
//! Numbers in error messages, in the shortest %g form ("1e-05", "0.6"), not std::to_string's
//! fixed six decimals ("0.000010").
#include <sstream>
#include <string>

namespace mpm {

inline std::string number_text(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

}  // namespace mpm
