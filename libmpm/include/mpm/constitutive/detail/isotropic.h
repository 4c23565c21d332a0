#pragma once
//! Isotropic elasticity written in principal (SVD) space, shared by every elastic model.
//!
//! An isotropic energy psi(F) = psihat(sigma) of the rotation-variant singular values
//! (math/svd.h) has P = U diag(p) V^T with p_i = d psihat / d sigma_i. Writing a perturbation
//! in the SVD frame, M = U^T dF V, the differential is dP = U D V^T with
//!   D_ii = sum_j (dp_i / dsigma_j) M_jj
//!   D_ij = (p_i - p_j)/(sigma_i - sigma_j) (M_ij + M_ji)/2
//!        + (p_i + p_j)/(sigma_i + sigma_j) (M_ij - M_ji)/2          (i != j)
//! (Stomakhin et al. 2012, supplement; the derivation differentiates U and V as rotations).
//! Each model supplies p, the Hessian dp/dsigma and the two quotients in a form that stays
//! finite when singular values coincide; the second quotient is singular where
//! sigma_i = -sigma_j (an inverted F), and is evaluated with safe_denominator().
//!
//! The map M -> D is block diagonal: the dim x dim block dp/dsigma on diag(M), and for each
//! pair i < j a 2 x 2 block on (M_ij, M_ji) with eigenvalues sym_ij and skew_ij. Clamping the
//! eigenvalues of every block at zero makes the differential positive semi-definite (Teran et
//! al. 2005), which an implicit step needs where the energy is not convex (compression,
//! inversion): make_positive_semidefinite().
//!
//! Inversion handling (Irving et al. 2004; Zhu et al. sec. 5.3): the models built on log sigma
//! (Neo-Hookean, Hencky) take it through extended_log, which below the critical stretch
//! inversion_clamp continues log by its second-order Taylor polynomial. The energy then stays
//! finite, C2 and restoring for flat (sigma = 0) and inverted (sigma < 0) particles, and its
//! gradient is still the stress, as Newton's line search requires; for sigma >= the clamp the
//! model is unchanged.
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace mpm::constitutive {

//! Critical stretch below which the logarithmic models continue their energy quadratically.
inline constexpr double inversion_clamp = 0.1;

namespace detail {

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

//! log x for x >= c = inversion_clamp, and below it log c + (x - c)/c - (x - c)^2 / (2 c^2):
//! value, first and second derivative. Increasing everywhere (L' >= 1/c below c).
struct ExtendedLog {
  double value, first, second;
  explicit ExtendedLog(double x) {
    constexpr double c = inversion_clamp;
    if (x >= c) {
      value = std::log(x);
      first = 1.0 / x;
      second = -first * first;
    } else {
      const double d = (x - c) / c;
      value = std::log(c) + d - 0.5 * d * d;
      first = (1.0 - d) / c;
      second = -1.0 / (c * c);
    }
  }
};

//! ExtendedLog of every singular value.
template <int dim>
struct ExtendedLogs {
  Vec<dim> value, first, second;
  explicit ExtendedLogs(const Vec<dim>& sigma) {
    for (int i = 0; i < dim; ++i) {
      const ExtendedLog l(sigma(i));
      value(i) = l.value;
      first(i) = l.first;
      second(i) = l.second;
    }
  }
};

//! (f(a) - f(b)) / (a - b), or f'((a + b)/2) where a and b are too close for the quotient
//! (second-order accurate; the quotient would lose digits to cancellation).
template <class DF>
double divided_difference(double a, double b, double fa, double fb, const DF& derivative) {
  if (std::abs(a - b) > 1e-6 * (std::abs(a) + std::abs(b))) return (fa - fb) / (a - b);
  return derivative(0.5 * (a + b));
}

//! D of the header comment for M = U^T dF V, back in world axes.
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

//! Clamps the eigenvalues of every block of the differential at zero (Teran et al. 2005): the
//! result is positive semi-definite and equals the input where that already was.
template <int dim>
void make_positive_semidefinite(PrincipalDifferential<dim>& d) {
  const Eigen::SelfAdjointEigenSolver<Mat<dim>> eigen(d.dp_dsigma);
  if (eigen.eigenvalues().minCoeff() < 0.0)
    d.dp_dsigma =
        eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
  d.sym = d.sym.cwiseMax(0.0);
  d.skew = d.skew.cwiseMax(0.0);
}

}  // namespace detail

//! The stress differential of one particle, prepared once (SVD and principal quantities) and
//! applied to many perturbations: the Hessian-vector products of an implicit solve.
template <int dim>
struct StressDerivative {
  math::Svd<dim> f;
  detail::PrincipalDifferential<dim> d;
  //! dP = (d^2 psi / dF dF) : dF [Pa].
  Mat<dim> apply(const Mat<dim>& dF) const { return detail::principal_differential(f, d, dF); }
};

//! The energy, stress and differential of a model that supplies principal_energy,
//! principal_stress and principal_hessian of its singular values.
template <class Model, int dim>
double isotropic_energy(const Model& model, const Mat<dim>& F) {
  return model.principal_energy(math::svd(F).sigma);
}

template <class Model, int dim>
Mat<dim> isotropic_first_piola(const Model& model, const Mat<dim>& F) {
  const math::Svd<dim> f = math::svd(F);
  return math::scaled_product<dim>(f.U, model.principal_stress(f.sigma), f.V);
}

//! Kirchhoff stress tau = P F^T = U diag(p_i sigma_i) U^T from the SVD f of F (the return maps
//! have it at hand: stages::ReturnMap fills the stress cache with it).
template <class Model, int dim>
Mat<dim> isotropic_kirchhoff(const Model& model, const math::Svd<dim>& f) {
  return math::scaled_product<dim>(f.U, model.principal_stress(f.sigma).cwiseProduct(f.sigma), f.U);
}

//! The differential at F; with `definite` made positive semi-definite (Teran et al. 2005).
template <class Model, int dim>
StressDerivative<dim> stress_derivative(const Model& model, const Mat<dim>& F, bool definite) {
  StressDerivative<dim> s{math::svd(F), {}};
  s.d = model.principal_hessian(s.f.sigma);
  if (definite) detail::make_positive_semidefinite(s.d);
  return s;
}

}  // namespace mpm::constitutive
