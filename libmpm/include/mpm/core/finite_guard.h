#pragma once
//! The NaN/Inf guard: stops a run naming the stage, the particle (or node) and the quantity.
#include <mpm/core/error.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <type_traits>
#include <vector>

namespace mpm {

template <class T>
bool is_finite_value(const T& value) {
  if constexpr (std::is_arithmetic_v<T>)
    return std::isfinite(value);
  else
    return value.allFinite();
}

//! Whether all of the n doubles at `values` are finite: their exponent bits tested in blocks,
//! in parallel, without a branch per value (a check after every stage costs a few per cent of a
//! step when done value by value on one thread).
bool all_finite(const double* values, std::size_t n);

//! Throws NumericalError "stage 'g2p': particle 17 has non-finite velocity" for the first
//! non-finite entry of `values`; `item` is "particle" or "node".
template <class T>
void check_finite(const std::vector<T>& values, const std::string& stage, const std::string& item,
                  const std::string& quantity) {
  if constexpr (std::is_same_v<T, double>) {
    if (all_finite(values.data(), values.size())) return;
  } else if constexpr (!std::is_arithmetic_v<T>) {
    if constexpr (std::is_same_v<typename T::Scalar, double> && T::SizeAtCompileTime > 0 &&
                  sizeof(T) == T::SizeAtCompileTime * sizeof(double))  // fixed size, no padding
      if (all_finite(values.data()->data(), values.size() * T::SizeAtCompileTime)) return;
  }
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!is_finite_value(values[i]))
      throw NumericalError("stage '" + stage + "': " + item + " " + std::to_string(i) + " has non-finite " + quantity);
}

}  // namespace mpm
