#pragma once
//! Stress differential of an isotropic model written in principal (SVD) space.
//!
//! An isotropic energy psi(F) = psihat(sigma) of the rotation-variant singular values
//! (math/svd.h) has P = U diag(p) V^T with p_i = d psihat / d sigma_i. Writing a perturbation
//! in the SVD frame, M = U^T dF V, the differential is dP = U D V^T with
//!   D_ii = sum_j (dp_i / dsigma_j) M_jj
//!   D_ij = (p_i - p_j)/(sigma_i - sigma_j) (M_ij + M_ji)/2
//!        + (p_i + p_j)/(sigma_i + sigma_j) (M_ij - M_ji)/2          (i != j)
//! (Stomakhin et al. 2012, supplement; the derivation differentiates U and V as rotations).
//! Each model supplies the two quotients in a form that stays finite when singular values
//! coincide; the second one is singular where sigma_i = -sigma_j (an inverted F), and the
//! models evaluate it with safe_denominator().
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <cmath>

namespace mpm::constitutive::detail {

template <int dim>
struct PrincipalDifferential {
  Mat<dim> dp_dsigma;  //!< Hessian of psihat in sigma [Pa]
  Mat<dim> sym;        //!< (p_i - p_j)/(sigma_i - sigma_j), off-diagonal entries used [Pa]
  Mat<dim> skew;       //!< (p_i + p_j)/(sigma_i + sigma_j), off-diagonal entries used [Pa]
};

//! Smallest stretch magnitude the principal-space formulas divide by; below it they use this
//! value, so that crushed or exactly inverted elements give large finite stresses, not Inf/NaN.
inline constexpr double min_stretch = 1e-6;

//! x with its magnitude raised to min_stretch, sign kept (0 counts as positive).
inline double safe_denominator(double x) { return std::abs(x) >= min_stretch ? x : std::copysign(min_stretch, x); }

template <int dim>
Mat<dim> principal_differential(const math::Svd<dim>& f, const PrincipalDifferential<dim>& d, const Mat<dim>& dF) {
  const Mat<dim> M = f.U.transpose() * dF * f.V;
  Mat<dim> D;
  for (int i = 0; i < dim; ++i) {
    D(i, i) = d.dp_dsigma.row(i).dot(M.diagonal());
    for (int j = 0; j < dim; ++j) {
      if (j == i) continue;
      D(i, j) = 0.5 * d.sym(i, j) * (M(i, j) + M(j, i)) + 0.5 * d.skew(i, j) * (M(i, j) - M(j, i));
    }
  }
  return f.U * D * f.V.transpose();
}

}  // namespace mpm::constitutive::detail
