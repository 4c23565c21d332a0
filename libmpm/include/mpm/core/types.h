#pragma once
//! Small fixed-size linear-algebra types shared by every library (SI units throughout).
#include <Eigen/Core>
#include <cstdint>

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

}  // namespace mpm
