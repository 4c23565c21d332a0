#pragma once
//! Compressible Neo-Hookean elasticity (Bonet and Wood 2008).
//!
//!   psi(F) = mu/2 (tr(F^T F) - d) - mu log J + lambda/2 (log J)^2        [J/m^3]
//!          = mu/2 sum_i (sigma_i^2 - 1) - mu sum_i L_i + lambda/2 (sum_i L_i)^2
//!   p_i    = mu sigma_i + (lambda sum_k L_k - mu) L'_i
//!
//! in the rotation-variant singular values, with L_i = log sigma_i, so that log J = sum_i L_i.
//! The energy is infinite for J <= 0; L is the extended logarithm of detail/isotropic.h below
//! the critical stretch inversion_clamp, which keeps energy and stress finite and restoring for
//! flat and inverted particles (Irving et al. 2004). For every sigma_i >= inversion_clamp this
//! is the textbook model.
#include <mpm/constitutive/detail/isotropic.h>
#include <mpm/core/types.h>

#include <string_view>

namespace mpm::constitutive {

template <int dim>
struct NeoHookean {
  static constexpr std::string_view name = "neo_hookean";

  double mu = 0.0;      //!< [Pa]
  double lambda = 0.0;  //!< [Pa]

  double energy(const Mat<dim>& F) const { return isotropic_energy(*this, F); }
  Mat<dim> first_piola(const Mat<dim>& F) const { return isotropic_first_piola(*this, F); }
  Mat<dim> first_piola_differential(const Mat<dim>& F, const Mat<dim>& dF) const {
    return stress_derivative(*this, F, false).apply(dF);
  }

  double principal_energy(const Vec<dim>& s) const {
    const double log_J = detail::ExtendedLogs<dim>(s).value.sum();
    return 0.5 * mu * (s.squaredNorm() - dim) - mu * log_J + 0.5 * lambda * log_J * log_J;
  }

  Vec<dim> principal_stress(const Vec<dim>& s) const {
    const detail::ExtendedLogs<dim> L(s);
    return mu * s + (lambda * L.value.sum() - mu) * L.first;
  }

  detail::PrincipalDifferential<dim> principal_hessian(const Vec<dim>& s) const {
    const detail::ExtendedLogs<dim> L(s);
    const double a = lambda * L.value.sum() - mu;  // the factor of L'_i in p_i
    detail::PrincipalDifferential<dim> d{Mat<dim>::Zero(), Mat<dim>::Zero(), Mat<dim>::Zero()};
    d.dp_dsigma = lambda * L.first * L.first.transpose();
    d.dp_dsigma.diagonal() += (Vec<dim>::Constant(mu) + a * L.second);
    for (int i = 0; i < dim; ++i) {
      for (int j = 0; j < dim; ++j) {
        if (i == j) continue;
        // Divided differences of L': exactly -1/(s_i s_j) and (1/s_i + 1/s_j)/(s_i + s_j) =
        // 1/(s_i s_j) where both lie on the logarithm.
        const bool log_branch = s(i) >= inversion_clamp && s(j) >= inversion_clamp;
        const double dd_first =
            log_branch ? -1.0 / (s(i) * s(j))
                       : detail::divided_difference(s(i), s(j), L.first(i), L.first(j),
                                                    [](double x) { return detail::ExtendedLog(x).second; });
        const double sum_quotient =
            log_branch ? 1.0 / (s(i) * s(j)) : (L.first(i) + L.first(j)) / detail::safe_denominator(s(i) + s(j));
        d.sym(i, j) = mu + a * dd_first;
        d.skew(i, j) = mu + a * sum_quotient;
      }
    }
    return d;
  }
};

}  // namespace mpm::constitutive
