#pragma once
//! Drucker-Prager return map for granular materials (Gao et al. 2017 sec. 4.2.1; Klar et al.
//! 2016) with the volume correction of Tampubolon et al. 2017.
//!
//! Yield function on the Kirchhoff stress tau of the Hencky StVK model (hencky_stvk.h):
//!   y(tau) = ||dev tau||_F + alpha tr(tau) - k <= 0,
//!   alpha = sqrt(2/3) 2 sin(phi) / (3 - sin(phi)),   k = sqrt(2/3) 6 c cos(phi) / (3 - sin(phi)),
//! the cone circumscribing the Mohr-Coulomb surface of friction angle phi and cohesion c; its
//! apex lies at tr(tau) = k / alpha = 3 c cot(phi) (tension), at tr(tau) = 0 without cohesion.
//! 2D uses the same constants with the 2D deviator, as Klar et al. do.
//!
//! The map works on the principal Hencky strain eps = log|sigma(Fe)|, where tau is linear:
//! dev tau = 2 mu dev eps, tr tau = (d lambda + 2 mu) tr eps. The flow is non-associative and
//! purely deviatoric (tr eps is kept), so three cases remain:
//!   I   y <= 0: elastic, Fe unchanged (or absorbing the stored correction, see below);
//!   II  the trial stress is beyond the apex (no deviatoric projection reaches the cone):
//!       eps = apex (expansion, the grains separate and carry no shear);
//!   III eps -= dgamma dev(eps)/||dev eps||, dgamma = y / (2 mu): back onto the cone.
//!
//! Volume correction. Case II discards volumetric strain, so under expansion the rest volume
//! of the material grows; compressing it back would then meet elastic resistance and the
//! material would gain volume. The per-particle state `plastic` = v stores the log volume
//! removed in case II, and v/d is added back to every trial strain: the material must first
//! be compressed by v before it develops pressure. With this, log det Fe + v equals the log of
//! the total volume change at all times (all three cases keep tr eps + v).
#include <mpm/constitutive/hencky_stvk.h>
#include <mpm/constitutive/lame.h>
#include <mpm/core/error.h>
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

namespace mpm::plasticity {

template <int dim>
class DruckerPrager {
public:
  static constexpr std::string_view name = "drucker_prager";

  //! friction_angle [deg] in [0, 90), cohesion [Pa] >= 0; lame of the Hencky StVK elasticity.
  DruckerPrager(double friction_angle, double cohesion, const constitutive::Lame& lame)
      : elastic_{lame.mu, lame.lambda} {
    verify<InputError>(
        friction_angle >= 0.0 && friction_angle < 90.0,
        "Drucker-Prager friction angle " + std::to_string(friction_angle) + " deg: expected a value in [0, 90)");
    verify<InputError>(cohesion >= 0.0,
                       "Drucker-Prager cohesion " + std::to_string(cohesion) + " Pa: expected a value >= 0");
    const double sin_phi = std::sin(friction_angle * std::numbers::pi / 180.0);
    const double cos_phi = std::cos(friction_angle * std::numbers::pi / 180.0);
    alpha_ = std::sqrt(2.0 / 3.0) * 2.0 * sin_phi / (3.0 - sin_phi);
    k_ = std::sqrt(2.0 / 3.0) * 6.0 * cohesion * cos_phi / (3.0 - sin_phi);
  }

  //! y of the Kirchhoff stress of Fe [Pa]; <= 0 is admissible.
  double yield_function(const Mat<dim>& Fe) const {
    return yield(elastic_.principal_kirchhoff(Hencky::principal_strain(math::svd(Fe).sigma)));
  }

  double modulus_scale(double /*plastic*/) const { return 1.0; }

  //! Projects Fe onto the admissible set and updates the volume correction `plastic` (log
  //! volume, >= 0). Returns whether Fe changed. A changed Fe has positive singular values.
  //! `result`, when given, receives the SVD of the Fe left (the trial's when unchanged).
  bool project(Mat<dim>& Fe, double& plastic, math::Svd<dim>* result = nullptr) const {
    math::Svd<dim> f = math::svd(Fe);
    const Vec<dim> eps = Hencky::principal_strain(f.sigma) + Vec<dim>::Constant(plastic / dim);
    const double trace = eps.sum();
    const double bulk = dim * elastic_.lambda + 2.0 * elastic_.mu;  // tr tau / tr eps
    Vec<dim> H = eps;
    if (alpha_ > 0.0 && alpha_ * bulk * trace >= k_) {  // II: to the apex, store the excess
      const double apex_trace = k_ / (alpha_ * bulk);
      H.setConstant(apex_trace / dim);
      plastic = std::max(trace - apex_trace, 0.0);
    } else {
      const double y = yield(elastic_.principal_kirchhoff(eps));
      if (y <= 0.0 && plastic == 0.0) {  // I, nothing stored to absorb
        if (result) *result = f;
        return false;
      }
      if (y > 0.0) {  // III
        const Vec<dim> dev = eps - Vec<dim>::Constant(trace / dim);
        H -= y / (2.0 * elastic_.mu * dev.norm()) * dev;
      }
      plastic = 0.0;
    }
    f.sigma = H.array().exp();
    Fe = f.U * f.sigma.asDiagonal() * f.V.transpose();
    if (result) *result = f;
    return true;
  }

private:
  using Hencky = constitutive::HenckyStVK<dim>;

  double yield(const Vec<dim>& tau) const {
    const double trace = tau.sum();
    return (tau - Vec<dim>::Constant(trace / dim)).norm() + alpha_ * trace - k_;
  }

  Hencky elastic_;
  double alpha_ = 0.0;  //!< friction coefficient [-]
  double k_ = 0.0;      //!< cohesive strength [Pa]
};

}  // namespace mpm::plasticity
