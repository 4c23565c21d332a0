#pragma once
// Test helper: angular momentum in 2D and 3D as 3-vectors (2D: the z component).
#include <mpm/core/types.h>

#include <Eigen/Core>

namespace mpm::test {

// The axial vector of the antisymmetric part of A: spin(B) = sum_i w (x_i - x_p) x v_i for
// B = sum_i w v_i (x_i - x_p)^T, and spin(C S) = sum r x (C r) for S = sum r r^T.
template <int dim>
Eigen::Vector3d spin(const Mat<dim>& A) {
  if constexpr (dim == 2)
    return Eigen::Vector3d(0.0, 0.0, A(1, 0) - A(0, 1));
  else
    return Eigen::Vector3d(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
}

// a x b.
template <int dim>
Eigen::Vector3d cross(const Vec<dim>& a, const Vec<dim>& b) {
  return spin<dim>(Mat<dim>(b * a.transpose()));
}

}  // namespace mpm::test
