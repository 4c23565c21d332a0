#include <mpm/solid/material.h>

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>

namespace mpm {

template <int dim>
double Material<dim>::wave_speed() const {
  return std::sqrt(lame.p_wave_modulus() / density);
}

template <int dim>
double Material<dim>::energy(const Mat<dim>& F, double plastic) const {
  return modulus_scale(plastic) * std::visit([&](const auto& model) { return model.energy(F); }, elastic);
}

template <int dim>
Mat<dim> Material<dim>::kirchhoff(const Mat<dim>& F, double plastic) const {
  return modulus_scale(plastic) *
         std::visit([&](const auto& model) -> Mat<dim> { return model.first_piola(F) * F.transpose(); }, elastic);
}

template <int dim>
double Material<dim>::modulus_scale(double plastic) const {
  return std::visit([&](const auto& model) { return model.modulus_scale(plastic); }, plasticity);
}

template <int dim>
Material<dim> parse_material(const Config& cfg) {
  Material<dim> material;
  material.name = cfg.text("name", "material");
  material.density = cfg.number("density", Range::positive());
  const double E = cfg.number("youngs_modulus", Range::positive());
  const double nu = cfg.number("poisson_ratio", Range::open(-1.0, 0.5));
  material.lame = constitutive::Lame::from_youngs_poisson(E, nu);
  const std::string elasticity = cfg.choice("elasticity", std::string(constitutive::FixedCorotated<dim>::name),
                                            constitutive::elastic_model_names());
  material.elastic = constitutive::make_elastic_model<dim>(elasticity, material.lame);

  const std::optional<Config> plastic = cfg.optional_child("plasticity");
  if (!plastic) return material;
  const std::string model =
      plastic->choice("model", std::string(plasticity::NoPlasticity::name), plasticity::plasticity_model_names());
  if (model == plasticity::NoPlasticity::name) return material;
  if (model == plasticity::Snow<dim>::name) {  // any elasticity (Stomakhin et al. use fixed-corotated)
    const double compression = plastic->number("critical_compression", 2.5e-2, Range::open(0.0, 1.0));
    const double stretch = plastic->number("critical_stretch", 7.5e-3, Range::positive());
    const double hardening = plastic->number("hardening", 10.0, Range::non_negative());
    material.plasticity = plasticity::Snow<dim>(compression, stretch, hardening);
    return material;
  }
  if (elasticity != constitutive::HenckyStVK<dim>::name) {
    plastic->fail("model", model +
                               " plasticity needs 'elasticity: " + std::string(constitutive::HenckyStVK<dim>::name) +
                               "' (its return map is closed-form in Hencky strain, Gao et al. 2017 "
                               "sec. 4.2), but the material has '" +
                               elasticity + "'");
  }
  if (model == plasticity::DruckerPrager<dim>::name) {
    const double friction_angle = plastic->number("friction_angle", 30.0, Range::half_open(0.0, 90.0));
    const double cohesion = plastic->number("cohesion", 0.0, Range::non_negative());
    // Dilatancy and mu(J) (drucker_prager.h): K = 0 is none, and a dilatant sand needs its
    // critical packing; without `rate` the friction is rate independent.
    typename plasticity::DruckerPrager<dim>::Flow flow;
    flow.dilatancy = plastic->number("dilatancy", 0.0, Range::non_negative());
    if (flow.dilatancy > 0.0)
      flow.critical_packing = plastic->number("critical_packing", Range::open(0.0, 1.0));
    else if (plastic->has("critical_packing"))
      plastic->fail("critical_packing", "a critical packing needs a dilatancy coefficient > 0 (key 'dilatancy')");
    const plasticity::DruckerPrager<dim> rate_independent(friction_angle, cohesion, material.lame);
    if (const std::optional<Config> rate = plastic->optional_child("rate")) {
      const double mu_1 = rate_independent.friction();
      flow.mu_2 = rate->number("mu_2", Range::closed(mu_1, 1e6));  // the message names mu_1's bound
      // The inertial number I (dry grains) when a grain diameter is given, else the viscous J.
      if (rate->has("grain_diameter")) {
        for (const char* viscous : {"j_0", "viscosity", "suspension", "j_min"})
          if (rate->has(viscous))
            rate->fail(viscous,
                       "belongs to the viscous number J; with grain_diameter the friction follows the "
                       "inertial number I (keys i_0, grain_diameter, grain_density)");
        flow.grain_diameter = rate->number("grain_diameter", Range::positive());
        flow.grain_density = rate->number("grain_density", material.density, Range::positive());
        flow.j_0 = rate->number("i_0", 0.279, Range::positive());
      } else {
        if (rate->has("i_0") || rate->has("grain_density"))
          rate->fail(rate->has("i_0") ? "i_0" : "grain_density",
                     "belongs to the inertial number I, which needs grain_diameter");
        flow.j_0 = rate->number("j_0", 0.005, Range::positive());
        flow.viscosity = rate->number("viscosity", Range::positive());
        // Boyer's suspension viscosity below jamming needs the critical packing of dilatancy.
        flow.suspension = rate->flag("suspension", false);
        if (flow.suspension && flow.dilatancy == 0.0)
          rate->fail("suspension",
                     "the suspension viscosity needs dilatancy (keys plasticity.dilatancy > 0 and "
                     "plasticity.critical_packing)");
        if (flow.suspension)
          flow.j_min = rate->number("j_min", 1e-3, Range::open(0.0, 1.0));
        else if (rate->has("j_min"))
          rate->fail("j_min", "belongs to the suspension viscosity (key suspension: true)");
      }
    }
    material.plasticity = plasticity::DruckerPrager<dim>(friction_angle, cohesion, material.lame, flow);
  } else if (model == plasticity::VonMises<dim>::name) {
    const double yield_stress = plastic->number("yield_stress", Range::positive());
    material.plasticity = plasticity::VonMises<dim>(yield_stress, material.lame);
  } else {
    // A model added to plasticity_model_names() must be given its keys here, not read as another.
    throw std::logic_error("parse_material: plasticity model '" + model + "' is accepted but has no parser");
  }
  return material;
}

template struct Material<2>;
template struct Material<3>;
template Material<2> parse_material<2>(const Config&);
template Material<3> parse_material<3>(const Config&);

}  // namespace mpm
