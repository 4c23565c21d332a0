#pragma once
//! Rotation-variant SVD and polar decomposition of 2x2 and 3x3 matrices.
//!
//! F = U diag(sigma) V^T with U and V proper rotations (det = +1). The singular values are
//! ordered |sigma_0| >= ... >= |sigma_{d-1}|; all are >= 0 except the last, which carries the
//! sign of det F. An inverted F (det F < 0) therefore keeps rotations in U and V and shows up
//! as one negative singular value, which is what invertible elasticity needs (Irving et al.
//! 2004; Stomakhin et al. 2012): R = U V^T is the closest proper rotation to F also when F is
//! inverted. Repeated and zero singular values are handled by Eigen's two-sided Jacobi SVD,
//! whose factors are then fixed up to proper rotations.
#include <mpm/core/types.h>

#include <Eigen/LU>
#include <Eigen/SVD>

namespace mpm::math {

template <int dim>
struct Svd {
  Mat<dim> U;
  Vec<dim> sigma;
  Mat<dim> V;
};

//! Polar decomposition F = R S, R a proper rotation, S symmetric (indefinite when det F < 0).
template <int dim>
struct Polar {
  Mat<dim> R;
  Mat<dim> S;
};

template <int dim>
Svd<dim> svd(const Mat<dim>& F) {
  const Eigen::JacobiSVD<Mat<dim>, Eigen::NoQRPreconditioner> jacobi(F, Eigen::ComputeFullU |
                                                                           Eigen::ComputeFullV);
  Svd<dim> result{jacobi.matrixU(), jacobi.singularValues(), jacobi.matrixV()};
  // Eigen returns orthogonal factors with det = +-1 and sigma >= 0. A reflection in U or V is
  // moved onto the smallest singular value, where it perturbs F the least.
  if (result.U.determinant() < 0) {
    result.U.col(dim - 1) *= -1;
    result.sigma(dim - 1) *= -1;
  }
  if (result.V.determinant() < 0) {
    result.V.col(dim - 1) *= -1;
    result.sigma(dim - 1) *= -1;
  }
  return result;
}

template <int dim>
Polar<dim> polar(const Mat<dim>& F) {
  const Svd<dim> f = svd(F);
  return {f.U * f.V.transpose(), f.V * f.sigma.asDiagonal() * f.V.transpose()};
}

}  // namespace mpm::math
