#pragma once
//! Rotation-variant SVD and polar decomposition of 2x2 and 3x3 matrices.
//!
//! F = U diag(sigma) V^T with U and V proper rotations (det = +1). The singular values are
//! ordered |sigma_0| >= ... >= |sigma_{d-1}|; all are >= 0 except the last, which carries the
//! sign of det F. An inverted F (det F < 0) therefore keeps rotations in U and V and shows up
//! as one negative singular value, which is what invertible elasticity needs (Irving et al.
//! 2004; Stomakhin et al. 2012): R = U V^T is the closest proper rotation to F also when F is
//! inverted. In 3D, repeated and zero singular values are handled by Eigen's two-sided Jacobi
//! SVD, whose factors are then fixed up to proper rotations; in 2D a closed form is exact and
//! several times faster (svd2 below).
#include <mpm/core/types.h>

#include <Eigen/LU>
#include <Eigen/SVD>
#include <cmath>

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

//! Closed-form 2x2 SVD: the polar rotation R(theta), theta = atan2(F10 - F01, F00 + F11),
//! makes S = R^T F symmetric with tr S >= 0; one Jacobi rotation V(phi), phi = atan2(2 S01,
//! S00 - S11) / 2, diagonalises S with eigenvalues s0 >= s1 and s0 + s1 >= 0, so |s0| >= |s1|
//! and only s1 can be negative. Then F = (R V) diag(s) V^T.
inline Svd<2> svd2(const Mat<2>& F) {
  const double theta = std::atan2(F(1, 0) - F(0, 1), F(0, 0) + F(1, 1));
  const double c = std::cos(theta), s = std::sin(theta);
  const double s00 = c * F(0, 0) + s * F(1, 0), s11 = -s * F(0, 1) + c * F(1, 1);
  const double s01 = c * F(0, 1) + s * F(1, 1);
  const double phi = 0.5 * std::atan2(2.0 * s01, s00 - s11);
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double mean = 0.5 * (s00 + s11), radius = std::hypot(0.5 * (s00 - s11), s01);
  Svd<2> r;
  r.V << cp, -sp, sp, cp;
  r.sigma << mean + radius, mean - radius;
  Mat<2> R;
  R << c, -s, s, c;
  r.U = R * r.V;
  return r;
}

template <int dim>
Svd<dim> svd(const Mat<dim>& F) {
  if constexpr (dim == 2) {
    return svd2(F);
  } else {
    const Eigen::JacobiSVD<Mat<dim>, Eigen::NoQRPreconditioner> jacobi(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Svd<dim> result{jacobi.matrixU(), jacobi.singularValues(), jacobi.matrixV()};
    // Eigen returns orthogonal factors with det = +-1 and sigma >= 0. A reflection in U or V
    // is moved onto the smallest singular value, where it perturbs F the least.
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
}

template <int dim>
Polar<dim> polar(const Mat<dim>& F) {
  const Svd<dim> f = svd(F);
  return {f.U * f.V.transpose(), f.V * f.sigma.asDiagonal() * f.V.transpose()};
}

}  // namespace mpm::math
