#pragma once
//! The elasticity models a scene can choose, as one closed std::variant. Stages std::visit it
//! once, outside the particle loop, so the per-particle call is static (no virtual dispatch).
//! Adding a model: its header, one alternative here, its name in elastic_model_names().
#include <mpm/constitutive/fixed_corotated.h>
#include <mpm/constitutive/hencky_stvk.h>
#include <mpm/constitutive/lame.h>
#include <mpm/constitutive/neo_hookean.h>
#include <mpm/core/error.h>

#include <string>
#include <variant>
#include <vector>

namespace mpm::constitutive {

template <int dim>
using ElasticModel = std::variant<FixedCorotated<dim>, NeoHookean<dim>, HenckyStVK<dim>>;

//! Scene-file names of the alternatives, in variant order.
inline std::vector<std::string> elastic_model_names() {
  return {std::string(FixedCorotated<3>::name), std::string(NeoHookean<3>::name), std::string(HenckyStVK<3>::name)};
}

//! The alternative called `name` with the given Lamé parameters.
template <int dim>
ElasticModel<dim> make_elastic_model(const std::string& name, const Lame& lame) {
  if (name == FixedCorotated<dim>::name) return FixedCorotated<dim>{lame.mu, lame.lambda};
  if (name == NeoHookean<dim>::name) return NeoHookean<dim>{lame.mu, lame.lambda};
  if (name == HenckyStVK<dim>::name) return HenckyStVK<dim>{lame.mu, lame.lambda};
  throw InputError("unknown elasticity model '" + name + "'");
}

}  // namespace mpm::constitutive
