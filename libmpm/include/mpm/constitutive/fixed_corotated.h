#pragma once
//! Fixed-corotated elasticity (Stomakhin et al. 2012; Gao et al. 2017 sec. 4.1).
//!
//!   psi(F) = mu ||F - R||_F^2 + lambda/2 (J - 1)^2                        [J/m^3]
//!          = mu sum_i (sigma_i - 1)^2 + lambda/2 (J - 1)^2
//!   P      = 2 mu (F - R) + lambda (J - 1) J F^-T
//!
//! with F = R S the polar decomposition (R proper) and sigma the rotation-variant singular
//! values, J = det F = prod sigma_i. Inverted F (J < 0) is well defined: the energy keeps
//! pushing the negative singular value back through zero, so the model needs no clamp.
#include <mpm/constitutive/detail/isotropic.h>
#include <mpm/core/types.h>

#include <string_view>

namespace mpm::constitutive {

template <int dim>
struct FixedCorotated {
  static constexpr std::string_view name = "fixed_corotated";

  double mu = 0.0;      //!< [Pa]
  double lambda = 0.0;  //!< [Pa]

  double energy(const Mat<dim>& F) const { return isotropic_energy(*this, F); }
  Mat<dim> first_piola(const Mat<dim>& F) const { return isotropic_first_piola(*this, F); }
  Mat<dim> first_piola_differential(const Mat<dim>& F, const Mat<dim>& dF) const {
    return stress_derivative(*this, F, false).apply(dF);
  }

  double principal_energy(const Vec<dim>& s) const {
    const double J = s.prod();
    return mu * (s.array() - 1.0).square().sum() + 0.5 * lambda * (J - 1.0) * (J - 1.0);
  }

  //! p_i = dpsi/dsigma_i
  Vec<dim> principal_stress(const Vec<dim>& s) const {
    const double J = s.prod();
    return 2.0 * mu * (s.array() - 1.0).matrix() + lambda * (J - 1.0) * dJ_dsigma(s);
  }

  detail::PrincipalDifferential<dim> principal_hessian(const Vec<dim>& s) const {
    const double J = s.prod();
    const Vec<dim> dJ = dJ_dsigma(s);
    detail::PrincipalDifferential<dim> d{Mat<dim>::Zero(), Mat<dim>::Zero(), Mat<dim>::Zero()};
    for (int i = 0; i < dim; ++i) {
      for (int j = 0; j < dim; ++j) {
        d.dp_dsigma(i, j) = lambda * dJ(i) * dJ(j);
        if (i == j) {
          d.dp_dsigma(i, i) += 2.0 * mu;
          continue;
        }
        const double q = d2J_dsigma2(s, i, j);
        d.dp_dsigma(i, j) += lambda * (J - 1.0) * q;
        d.sym(i, j) = 2.0 * mu - lambda * (J - 1.0) * q;
        d.skew(i, j) = 2.0 * mu - 4.0 * mu / detail::safe_denominator(s(i) + s(j)) + lambda * (J - 1.0) * q;
      }
    }
    return d;
  }

private:
  //! dJ/dsigma_i = prod_{k != i} sigma_k, computed without dividing by sigma_i.
  static Vec<dim> dJ_dsigma(const Vec<dim>& s) {
    if constexpr (dim == 2) {
      return Vec<dim>(s(1), s(0));
    } else {
      return Vec<dim>(s(1) * s(2), s(2) * s(0), s(0) * s(1));
    }
  }

  //! d^2 J / dsigma_i dsigma_j = prod_{k != i, j} sigma_k for i != j.
  static double d2J_dsigma2(const Vec<dim>& s, int i, int j) {
    if constexpr (dim == 2) {
      return 1.0;
    } else {
      return s(3 - i - j);
    }
  }
};

}  // namespace mpm::constitutive
