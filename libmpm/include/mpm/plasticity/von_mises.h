#pragma once
//! Von Mises return map for perfectly plastic metals and goo (Gao et al. 2017 sec. 4.2.2).
//!
//! Yield function on the Kirchhoff stress tau of the Hencky StVK model (hencky_stvk.h):
//!   y(tau) = sqrt(3/2) ||dev tau||_F - sigma_y <= 0          (= sqrt(3 J2) - sigma_y in 3D)
//! In 2D, dev is the 2D deviator and the same sqrt(3/2) scaling is kept, so that in-plane pure
//! shear tau = diag(s, -s) yields at s = sigma_y / sqrt(3), as in 3D.
//!
//! Associative flow in principal Hencky strain eps = log|sigma(Fe)| (dev tau = 2 mu dev eps):
//!   H = eps - dgamma dev(eps) / ||dev eps||,   dgamma = ||dev eps|| - sqrt(2/3) sigma_y / (2 mu).
//! Sec. 4.2.2 prints dgamma without the factor sqrt(2/3); that version stops at
//! ||dev tau|| = sigma_y, outside its own yield surface by the factor sqrt(3/2). With the factor
//! the projected state satisfies y = 0.
#include <mpm/constitutive/hencky_stvk.h>
#include <mpm/constitutive/lame.h>
#include <mpm/core/error.h>
#include <mpm/core/types.h>
#include <mpm/math/svd.h>

#include <cmath>
#include <string>
#include <string_view>

namespace mpm::plasticity {

template <int dim>
class VonMises {
public:
  static constexpr std::string_view name = "von_mises";

  //! yield_stress [Pa] > 0; lame of the Hencky StVK elasticity.
  VonMises(double yield_stress, const constitutive::Lame& lame)
      : elastic_{lame.mu, lame.lambda}, yield_stress_(yield_stress) {
    verify<InputError>(yield_stress > 0.0,
                       "von Mises yield stress " + std::to_string(yield_stress) + " Pa: expected > 0");
  }

  double modulus_scale(double /*plastic*/) const { return 1.0; }
  double yield_stress() const { return yield_stress_; }  //!< [Pa]

  //! y of the Kirchhoff stress of Fe [Pa]; <= 0 is admissible.
  double yield_function(const Mat<dim>& Fe) const {
    return yield(deviator(Hencky::principal_strain(math::svd(Fe).sigma)));
  }

  //! Projects Fe onto the yield surface; returns whether Fe changed (then its singular values
  //! are positive). The model is perfectly plastic and keeps no state: `plastic` is unchanged.
  bool project(Mat<dim>& Fe, double& plastic, math::Svd<dim>* result = nullptr) const {
    return project(Fe, math::svd(Fe), plastic, result);
  }

  //! The same given f = math::svd(Fe) (stages::ReturnMap takes the SVDs of several at once);
  //! `log_sigma`, when given, receives the log of the result's singular values.
  bool project(Mat<dim>& Fe, math::Svd<dim> f, double& /*plastic*/, math::Svd<dim>* result = nullptr,
               Vec<dim>* log_sigma = nullptr) const {
    const Vec<dim> eps = Hencky::principal_strain(f.sigma);
    const Vec<dim> dev = deviator(eps);
    const double y = yield(dev);
    if (y <= 0.0) {
      if (result) *result = f;
      if (log_sigma) *log_sigma = eps;
      return false;
    }
    const Vec<dim> H = eps - y / (std::sqrt(1.5) * 2.0 * elastic_.mu * dev.norm()) * dev;
    f.sigma = Hencky::principal_stretch(H);
    Fe = math::scaled_product<dim>(f.U, f.sigma, f.V);
    if (result) *result = f;
    if (log_sigma) *log_sigma = H;
    return true;
  }

private:
  using Hencky = constitutive::HenckyStVK<dim>;

  static Vec<dim> deviator(const Vec<dim>& eps) { return eps - Vec<dim>::Constant(eps.sum() / dim); }

  //! y from the deviatoric Hencky strain: dev tau = 2 mu dev eps.
  double yield(const Vec<dim>& dev_eps) const {
    return std::sqrt(1.5) * 2.0 * elastic_.mu * dev_eps.norm() - yield_stress_;
  }

  Hencky elastic_;
  double yield_stress_;  //!< [Pa]
};

}  // namespace mpm::plasticity
