#pragma once
//! St. Venant-Kirchhoff energy in Hencky strain (Gao et al. 2017 eq. 7; Mast et al. 2013), the
//! elastic response under Drucker-Prager and von Mises plasticity.
//!
//!   psi(F) = mu tr(log(Sigma)^2) + lambda/2 (tr log(Sigma))^2            [J/m^3]
//!          = mu sum_i eps_i^2 + lambda/2 (sum_i eps_i)^2,   eps_i = log|sigma_i|
//!   P      = U diag(tau_i / sigma_i) V^T,   tau_i = 2 mu eps_i + lambda sum_k eps_k
//!
//! with F = U diag(sigma) V^T the rotation-variant SVD; tau_i are the principal Kirchhoff
//! stresses (tau = P F^T = U diag(tau_i) U^T), linear in the principal Hencky strain, which is
//! what makes the return maps closed-form. |sigma_i| below detail::min_stretch is raised to it.
#include <mpm/constitutive/detail/isotropic.h>
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <cmath>
#include <string_view>

namespace mpm::constitutive {

template <int dim>
struct HenckyStVK {
  static constexpr std::string_view name = "hencky_stvk";
  //! Defined for det F < 0 through log|sigma| (a reflection carries no stress).
  static constexpr bool supports_inversion = true;

  double mu = 0.0;      //!< [Pa]
  double lambda = 0.0;  //!< [Pa]

  //! Principal Hencky strain eps_i = log|sigma_i| of the rotation-variant singular values.
  static Vec<dim> principal_strain(const Vec<dim>& sigma) { return safe(sigma).array().abs().log().matrix(); }

  //! Principal Kirchhoff stress tau_i = dpsi/deps_i [Pa].
  Vec<dim> principal_kirchhoff(const Vec<dim>& eps) const {
    return 2.0 * mu * eps + Vec<dim>::Constant(lambda * eps.sum());
  }

  double energy(const Mat<dim>& F) const {
    const Vec<dim> eps = principal_strain(math::svd(F).sigma);
    return mu * eps.squaredNorm() + 0.5 * lambda * eps.sum() * eps.sum();
  }

  Mat<dim> first_piola(const Mat<dim>& F) const {
    const math::Svd<dim> f = math::svd(F);
    const Vec<dim> tau = principal_kirchhoff(principal_strain(f.sigma));
    return f.U * tau.cwiseQuotient(safe(f.sigma)).asDiagonal() * f.V.transpose();
  }

  Mat<dim> first_piola_differential(const Mat<dim>& F, const Mat<dim>& dF) const {
    const math::Svd<dim> f = math::svd(F);
    const Vec<dim> s = safe(f.sigma);
    const Vec<dim> eps = principal_strain(f.sigma);
    const Vec<dim> p = principal_kirchhoff(eps).cwiseQuotient(s);
    detail::PrincipalDifferential<dim> d{Mat<dim>::Zero(), Mat<dim>::Zero(), Mat<dim>::Zero()};
    for (int i = 0; i < dim; ++i) {
      for (int j = 0; j < dim; ++j) {
        d.dp_dsigma(i, j) = ((i == j ? 2.0 * mu : 0.0) + lambda) / (s(i) * s(j));
        if (i == j) {
          d.dp_dsigma(i, i) -= p(i) / s(i);
          continue;
        }
        // p_i = (2 mu log|s_i| + lambda tr eps) / s_i: divided differences of log|x|/x and 1/x.
        d.sym(i, j) = 2.0 * mu * divided_log_over_x(s(i), s(j)) - lambda * eps.sum() / (s(i) * s(j));
        d.skew(i, j) = (p(i) + p(j)) / detail::safe_denominator(s(i) + s(j));
      }
    }
    return detail::principal_differential(f, d, dF);
  }

private:
  static Vec<dim> safe(const Vec<dim>& sigma) {
    return sigma.unaryExpr([](double x) { return detail::safe_denominator(x); });
  }

  //! (log|a| - log|b|) / (a - b), through log1p when a and b are close (same sign).
  static double divided_log(double a, double b) {
    if (a * b < 0) return (std::log(std::abs(a)) - std::log(std::abs(b))) / (a - b);
    const double x = (a - b) / b;
    return x == 0.0 ? 1.0 / b : std::log1p(x) / (x * b);
  }

  //! (g(a) - g(b)) / (a - b) for g(x) = log|x| / x, without cancellation when a ~ b.
  static double divided_log_over_x(double a, double b) {
    return (b * divided_log(a, b) - std::log(std::abs(b))) / (a * b);
  }
};

}  // namespace mpm::constitutive
