#pragma once
//! Compressible Neo-Hookean elasticity (Bonet and Wood 2008).
//!
//!   psi(F) = mu/2 (tr(F^T F) - d) - mu log J + lambda/2 (log J)^2        [J/m^3]
//!   P      = mu F + (lambda log J - mu) J^-1 cof(F),     cof(F) = J F^-T
//!
//! The energy is infinite for J <= 0. The stress is evaluated inside hot particle loops, so
//! instead of throwing, J is replaced by Jhat = max(J, min_J) in the scalar coefficients (psi,
//! and the factor of cof F, which is defined for any F). A crushed or inverted element then gets
//! a large, finite stress that increases J; psi and P are exact for J >= min_J only, and the
//! differential is the exact derivative of this clamped P.
#include <mpm/constitutive/detail/cofactor.h>
#include <mpm/core/types.h>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <string_view>

namespace mpm::constitutive {

template <int dim>
struct NeoHookean {
  static constexpr std::string_view name = "neo_hookean";
  //! log J is undefined for det F <= 0: the stress stage stops naming the particle.
  static constexpr bool supports_inversion = false;
  static constexpr double min_J = 1e-6;

  double mu = 0.0;      //!< [Pa]
  double lambda = 0.0;  //!< [Pa]

  double energy(const Mat<dim>& F) const {
    const double log_J = std::log(std::max(F.determinant(), min_J));
    return 0.5 * mu * (F.squaredNorm() - dim) - mu * log_J + 0.5 * lambda * log_J * log_J;
  }

  Mat<dim> first_piola(const Mat<dim>& F) const {
    const double J = std::max(F.determinant(), min_J);
    return mu * F + (lambda * std::log(J) - mu) / J * detail::cofactor(F);
  }

  Mat<dim> first_piola_differential(const Mat<dim>& F, const Mat<dim>& dF) const {
    const double J = F.determinant();
    const double Jhat = std::max(J, min_J);
    const double log_J = std::log(Jhat);
    const Mat<dim> cof = detail::cofactor(F);
    // d/dJ of (lambda log J - mu)/J; zero where J is clamped.
    const double dcoef_dJ = J > min_J ? (lambda + mu - lambda * log_J) / (Jhat * Jhat) : 0.0;
    return mu * dF + dcoef_dJ * cof.cwiseProduct(dF).sum() * cof +
           (lambda * log_J - mu) / Jhat * detail::cofactor_differential(F, dF);
  }
};

}  // namespace mpm::constitutive
