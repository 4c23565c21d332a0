#pragma once
//! Snow plasticity (Stomakhin et al. 2013, sec. 5): the singular values of F^E are clamped to
//! [1 - theta_c, 1 + theta_s], the critical compression and stretch; what the clamp removes
//! goes to the plastic part F^P (kept as J^P = det F^P only, so det F^E J^P = det F stays),
//! and the material hardens under compaction:
//!   Sigma^ = clamp(Sigma, 1 - theta_c, 1 + theta_s),  F^E = U Sigma^ V^T,
//!   J^P <- J^P det(Sigma) / det(Sigma^),
//!   mu(J^P) = mu_0 e^{xi (1 - J^P)},  lambda(J^P) = lambda_0 e^{xi (1 - J^P)}.
//! The per-particle state `plastic` is log J^P (0: virgin snow). The hardening scales every
//! elastic modulus by the same factor, so the stress of any elastic model is multiplied by
//! modulus_scale(plastic); Stomakhin et al. pair it with fixed-corotated elasticity.
#include <mpm/core/error.h>
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>

namespace mpm::plasticity {

template <int dim>
class Snow {
public:
  static constexpr std::string_view name = "snow";

  //! critical_compression theta_c in (0, 1), critical_stretch theta_s > 0, hardening xi >= 0.
  Snow(double critical_compression, double critical_stretch, double hardening)
      : lo_(1.0 - critical_compression), hi_(1.0 + critical_stretch), hardening_(hardening) {
    verify<InputError>(critical_compression > 0.0 && critical_compression < 1.0,
                       "snow critical compression " + std::to_string(critical_compression) + ": expected (0, 1)");
    verify<InputError>(critical_stretch > 0.0,
                       "snow critical stretch " + std::to_string(critical_stretch) + ": expected > 0");
    verify<InputError>(hardening >= 0.0, "snow hardening " + std::to_string(hardening) + ": expected >= 0");
  }

  //! How far a singular value lies outside [1 - theta_c, 1 + theta_s] [-]; <= 0 admissible.
  double yield_function(const Mat<dim>& Fe) const {
    const Vec<dim> s = math::svd(Fe).sigma;
    return std::max(s.maxCoeff() - hi_, lo_ - s.minCoeff());
  }

  //! Clamps the singular values of Fe and moves the removed volume into log J^P (`plastic`).
  bool project(Mat<dim>& Fe, double& plastic, math::Svd<dim>* result = nullptr) const {
    return project(Fe, math::svd(Fe), plastic, result);
  }

  //! The same given f = math::svd(Fe) (stages::ReturnMap takes the SVDs of several at once).
  bool project(Mat<dim>& Fe, const math::Svd<dim>& f, double& plastic, math::Svd<dim>* result = nullptr) const {
    const Vec<dim> clamped = f.sigma.cwiseMax(lo_).cwiseMin(hi_);
    if (result) *result = math::Svd<dim>{f.U, clamped, f.V};
    if (clamped == f.sigma) return false;
    // An inverted F^E (sigma < 0) is clamped to lo_: its volume change has no logarithm, so
    // J^P takes the magnitude of the ratio.
    plastic += std::log(std::abs(f.sigma.prod()) / clamped.prod());
    Fe = math::scaled_product<dim>(f.U, clamped, f.V);
    return true;
  }

  //! e^{xi (1 - J^P)}, J^P = e^plastic: the factor of every elastic modulus.
  double modulus_scale(double plastic) const { return std::exp(hardening_ * (1.0 - std::exp(plastic))); }

private:
  double lo_, hi_, hardening_;
};

}  // namespace mpm::plasticity
