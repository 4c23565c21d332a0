#pragma once
//! Small fixed-size linear-algebra types shared by every library (SI units throughout).
#include <Eigen/Core>
#include <cstdint>
#include <utility>

namespace mpm {

template <int dim>
using Vec = Eigen::Matrix<double, dim, 1>;
template <int dim>
using Mat = Eigen::Matrix<double, dim, dim>;
template <int dim>
using IVec = Eigen::Matrix<int, dim, 1>;

using Index = std::int64_t;

//! Integer power for compile-time stencil sizes: ipow(3, dim) nodes in a quadratic stencil.
constexpr int ipow(int base, int exponent) { return exponent == 0 ? 1 : base * ipow(base, exponent - 1); }

//! Calls fn(i) for every integer point i of the box [lo, hi] (inclusive; none when empty),
//! the first axis fastest.
template <int dim, class Fn>
void for_each_in_box(const IVec<dim>& lo, const IVec<dim>& hi, Fn&& fn) {
  if ((lo.array() > hi.array()).any()) return;
  IVec<dim> i = lo;
  while (true) {
    fn(std::as_const(i));
    int a = 0;
    for (; a < dim; ++a) {
      if (++i[a] <= hi[a]) break;
      i[a] = lo[a];
    }
    if (a == dim) return;
  }
}

}  // namespace mpm
