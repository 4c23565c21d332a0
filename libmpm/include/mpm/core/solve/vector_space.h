#pragma once
//! The vector operations the Krylov solvers need, for std::vector of scalars (one unknown per
//! cell) and of fixed-size Eigen vectors (all components of a node velocity solved at once
//! with the same operator). Reductions run in index order, so a solve gives the same bits on
//! every run and thread count.
#include <Eigen/Core>

#include <cstddef>
#include <type_traits>
#include <vector>

namespace mpm::solve {

//! The additive identity of an element type.
template <class T>
T zero() {
  if constexpr (std::is_arithmetic_v<T>)
    return T(0);
  else
    return T::Zero();
}

//! The Euclidean inner product of two element values.
template <class T>
double inner(const T& a, const T& b) {
  if constexpr (std::is_arithmetic_v<T>)
    return a * b;
  else
    return a.dot(b);
}

//! The Euclidean inner product of two vectors of equal size.
template <class T>
double dot(const std::vector<T>& a, const std::vector<T>& b) {
  double s = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) s += inner(a[i], b[i]);
  return s;
}

}  // namespace mpm::solve
