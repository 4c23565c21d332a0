#pragma once
//! The NaN/Inf guard: stops a run naming the stage, the particle (or node) and the quantity.
#include <mpm/core/error.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
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

//! 1 when x is NaN or infinite (its exponent bits all ones), else 0: an integer test the
//! compiler vectorises, to be OR-ed over many values without a branch.
inline std::uint64_t non_finite_bit(double x) {
  constexpr std::uint64_t exponent = 0x7ff0000000000000ull;
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return static_cast<std::uint64_t>((bits & exponent) == exponent);
}

//! non_finite_bit OR-ed over a double or the coefficients of a fixed-size Eigen matrix of
//! doubles: 1 when any is NaN or infinite.
template <class T>
std::uint64_t non_finite_bits(const T& value) {
  if constexpr (std::is_same_v<T, double>) {
    return non_finite_bit(value);
  } else {
    static_assert(std::is_same_v<typename T::Scalar, double> && T::SizeAtCompileTime > 0);
    std::uint64_t any = 0;
    for (int k = 0; k < T::SizeAtCompileTime; ++k) any |= non_finite_bit(value.data()[k]);
    return any;
  }
}

//! Whether all of the n doubles at `values` are finite: their exponent bits tested in blocks,
//! in parallel, without a branch per value (a check after every stage costs a few per cent of a
//! step when done value by value on one thread).
bool all_finite(const double* values, std::size_t n);

//! Whether the entries `indices` [first, last) of `values` (doubles, or fixed-size Eigen
//! matrices of doubles) are finite: the exponent test of all_finite, for a pass that checks
//! what it has just written while it is in cache (a bucket of particles).
template <class T>
bool all_finite_at(const std::vector<T>& values, const std::uint32_t* first, const std::uint32_t* last) {
  std::uint64_t any = 0;
  for (const std::uint32_t* i = first; i != last; ++i) any |= non_finite_bits(values[*i]);
  return any == 0;
}

//! Throws NumericalError "stage 'g2p': particle 17 has non-finite velocity" for the first
//! non-finite entry of `values`; `item` is "particle" or "node".
template <class T>
void check_finite(const std::vector<T>& values, const std::string& stage, const std::string& item,
                  const std::string& quantity) {
  if (values.empty()) return;
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
