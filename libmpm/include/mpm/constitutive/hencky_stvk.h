#pragma once
//! St. Venant-Kirchhoff energy in Hencky strain (Gao et al. 2017 eq. 7; Mast et al. 2013), the
//! elastic response under Drucker-Prager and von Mises plasticity.
//!
//!   psi(F) = mu tr(log(Sigma)^2) + lambda/2 (tr log(Sigma))^2            [J/m^3]
//!          = mu sum_i L_i^2 + lambda/2 (sum_i L_i)^2
//!   p_i    = tau_i L'_i,   tau_i = 2 mu L_i + lambda sum_k L_k
//!
//! with F = U diag(sigma) V^T the rotation-variant SVD and L_i = log sigma_i the principal
//! Hencky strain; tau_i are the principal Kirchhoff stresses (tau = P F^T = U diag(tau_i) U^T),
//! linear in the strain, which is what makes the return maps closed-form. Below the critical
//! stretch inversion_clamp, L is the extended logarithm of detail/isotropic.h: a flat or
//! inverted particle (sigma_i <= 0) keeps a finite energy whose stress pushes it back.
#include <mpm/constitutive/detail/isotropic.h>
#include <mpm/core/types.h>

#include <cmath>
#include <string_view>

namespace mpm::constitutive {

template <int dim>
struct HenckyStVK {
  static constexpr std::string_view name = "hencky_stvk";

  double mu = 0.0;      //!< [Pa]
  double lambda = 0.0;  //!< [Pa]

  //! Principal Hencky strain eps_i = log|sigma_i| of the rotation-variant singular values, the
  //! variable of the return maps (|sigma_i| below detail::min_stretch is raised to it).
  static Vec<dim> principal_strain(const Vec<dim>& sigma) {
    return sigma.unaryExpr([](double x) { return std::log(std::abs(detail::safe_denominator(x))); });
  }
  //! The singular values sigma_i = exp(eps_i) of a principal Hencky strain (a return map's
  //! result). libm's exp per component: Eigen's packet exp costs more on three values (one
  //! two-lane packet and a scalar tail; bench_step's sand 1-4 % slower, docs/performance.md).
  static Vec<dim> principal_stretch(const Vec<dim>& eps) {
    Vec<dim> sigma;
    for (int a = 0; a < dim; ++a) sigma[a] = std::exp(eps[a]);
    return sigma;
  }

  //! Principal Kirchhoff stress tau_i = dpsi/deps_i [Pa].
  Vec<dim> principal_kirchhoff(const Vec<dim>& eps) const {
    return 2.0 * mu * eps + Vec<dim>::Constant(lambda * eps.sum());
  }

  //! Kirchhoff stress U diag(tau(L)) U^T of an F with SVD f, given L = log sigma (the return
  //! maps leave both): isotropic_kirchhoff(*this, f) without its logarithms and divisions where
  //! every sigma_i >= inversion_clamp (equal up to rounding), that function elsewhere.
  Mat<dim> kirchhoff(const math::Svd<dim>& f, const Vec<dim>& log_sigma) const {
    if (f.sigma.minCoeff() < inversion_clamp) return isotropic_kirchhoff(*this, f);
    return math::scaled_product<dim>(f.U, principal_kirchhoff(log_sigma), f.U);
  }

  double energy(const Mat<dim>& F) const { return isotropic_energy(*this, F); }
  Mat<dim> first_piola(const Mat<dim>& F) const { return isotropic_first_piola(*this, F); }
  Mat<dim> first_piola_differential(const Mat<dim>& F, const Mat<dim>& dF) const {
    return stress_derivative(*this, F, false).apply(dF);
  }

  double principal_energy(const Vec<dim>& s) const {
    const Vec<dim> L = detail::ExtendedLogs<dim>(s).value;
    return mu * L.squaredNorm() + 0.5 * lambda * L.sum() * L.sum();
  }

  Vec<dim> principal_stress(const Vec<dim>& s) const {
    const detail::ExtendedLogs<dim> L(s);
    return principal_kirchhoff(L.value).cwiseProduct(L.first);
  }

  detail::PrincipalDifferential<dim> principal_hessian(const Vec<dim>& s) const {
    const detail::ExtendedLogs<dim> L(s);
    const double trace = L.value.sum();
    const Vec<dim> tau = principal_kirchhoff(L.value);
    const Vec<dim> p = tau.cwiseProduct(L.first);
    detail::PrincipalDifferential<dim> d{Mat<dim>::Zero(), Mat<dim>::Zero(), Mat<dim>::Zero()};
    d.dp_dsigma = lambda * L.first * L.first.transpose();
    d.dp_dsigma.diagonal() += 2.0 * mu * L.first.cwiseAbs2() + tau.cwiseProduct(L.second);
    for (int i = 0; i < dim; ++i) {
      for (int j = 0; j < dim; ++j) {
        if (i == j) continue;
        // p_i = 2 mu g(s_i) + lambda tr L h(s_i) with g = L L', h = L': divided differences.
        double dd_g, dd_h;
        if (s(i) >= inversion_clamp && s(j) >= inversion_clamp) {
          dd_g = divided_log_over_x(s(i), s(j));
          dd_h = -1.0 / (s(i) * s(j));
        } else {
          const auto dg = [](double x) {
            const detail::ExtendedLog l(x);
            return l.first * l.first + l.value * l.second;
          };
          dd_g = detail::divided_difference(s(i), s(j), L.value(i) * L.first(i), L.value(j) * L.first(j), dg);
          dd_h = detail::divided_difference(s(i), s(j), L.first(i), L.first(j),
                                            [](double x) { return detail::ExtendedLog(x).second; });
        }
        d.sym(i, j) = 2.0 * mu * dd_g + lambda * trace * dd_h;
        d.skew(i, j) = (p(i) + p(j)) / detail::safe_denominator(s(i) + s(j));
      }
    }
    return d;
  }

private:
  //! (log a - log b) / (a - b) for a, b > 0, through log1p when a and b are close.
  static double divided_log(double a, double b) {
    const double x = (a - b) / b;
    return x == 0.0 ? 1.0 / b : std::log1p(x) / (x * b);
  }

  //! (g(a) - g(b)) / (a - b) for g(x) = log x / x, without cancellation when a ~ b.
  static double divided_log_over_x(double a, double b) { return (b * divided_log(a, b) - std::log(b)) / (a * b); }
};

}  // namespace mpm::constitutive
