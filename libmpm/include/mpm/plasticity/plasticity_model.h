#pragma once
//! The plastic return maps a scene can choose, as one closed std::variant (visited outside the
//! particle loop, like constitutive::ElasticModel). Each alternative offers
//!   bool project(Mat<dim>& Fe, double& plastic, math::Svd<dim>* result = nullptr) const;
//!                        // true when Fe changed; *result: the SVD of the Fe it leaves
//!                        // (the models work in that space; NoPlasticity fills none)
//!   double yield_function(const Mat<dim>& Fe) const;     // <= 0 admissible
//!   double modulus_scale(double plastic) const;          // factor of the elastic moduli
//! where `plastic` is the per-particle scalar state (Particles::plastic); modulus_scale is 1
//! except for a hardening model (snow).
#include <mpm/core/types.h>
#include <mpm/math/svd.h>
#include <mpm/plasticity/drucker_prager.h>
#include <mpm/plasticity/snow.h>
#include <mpm/plasticity/von_mises.h>

#include <limits>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace mpm::plasticity {

//! Purely elastic material: every state is admissible.
struct NoPlasticity {
  static constexpr std::string_view name = "none";

  template <int dim>
  bool project(Mat<dim>& /*Fe*/, double& /*plastic*/, math::Svd<dim>* /*result*/ = nullptr) const {
    return false;
  }
  template <int dim>
  double yield_function(const Mat<dim>& /*Fe*/) const {
    return -std::numeric_limits<double>::infinity();
  }
  double modulus_scale(double /*plastic*/) const { return 1.0; }
};

template <int dim>
using PlasticityModel = std::variant<NoPlasticity, DruckerPrager<dim>, VonMises<dim>, Snow<dim>>;

//! Scene-file names of the alternatives, in variant order.
inline std::vector<std::string> plasticity_model_names() {
  return {std::string(NoPlasticity::name), std::string(DruckerPrager<3>::name), std::string(VonMises<3>::name),
          std::string(Snow<3>::name)};
}

}  // namespace mpm::plasticity
