#pragma once
//! The NaN/Inf guard: stops a run naming the stage, the particle (or node) and the quantity.
#include <mpm/core/error.h>

#include <cmath>
#include <string>
#include <vector>

namespace mpm {

template <class T>
bool is_finite_value(const T& value) {
  if constexpr (std::is_arithmetic_v<T>)
    return std::isfinite(value);
  else
    return value.allFinite();
}

//! Throws NumericalError "stage 'g2p': particle 17 has non-finite velocity" for the first
//! non-finite entry of `values`; `item` is "particle" or "node".
template <class T>
void check_finite(const std::vector<T>& values, const std::string& stage, const std::string& item,
                  const std::string& quantity) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!is_finite_value(values[i]))
      throw NumericalError("stage '" + stage + "': " + item + " " + std::to_string(i) + " has non-finite " + quantity);
}

}  // namespace mpm
