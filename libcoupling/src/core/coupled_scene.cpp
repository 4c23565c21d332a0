#include <coupling/coupled_scene.h>
#include <coupling/stages/coupled_stages.h>
#include <coupling/stages/on_phase.h>
#include <fluid/stages/implicit_viscosity.h>
#include <mpm/core/error.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/deformation_update.h>
#include <mpm/solid/stages/return_map.h>
#include <mpm/solid/stages/stress_forces.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

namespace coupling {

template <int dim>
CoupledScene<dim> make_coupled_scene(mpm::SceneSettings<dim> settings,
                                     mpm::geometry::ColliderSet<dim> colliders,
                                     std::optional<fluid::FluidMaterial> fluid,
                                     fluid::stages::PressureSettings pressure,
                                     std::optional<SedimentPhase<dim>> sediment,
                                     std::optional<drag::DragLaw> drag) {
  mpm::verify<mpm::InputError>(fluid || sediment, "coupled scene: neither a fluid nor a sediment phase");
  mpm::verify<mpm::InputError>(!(fluid && sediment) || drag.has_value(),
                               "coupled scene: a fluid and a sediment phase need a drag law");
  mpm::verify<mpm::InputError>(!sediment || !sediment->switching || !sediment->materials.empty(),
                               "coupled scene: continuum/discrete switching needs a sediment material");
  // The volume fractions, the exchange and the mixture projection index nodes without the
  // periodic wrap of the fluid's own stages.
  for (int a = 0; a < dim; ++a)
    mpm::verify<mpm::InputError>(!settings.periodic[a], "coupled scene: no periodic axes (the fluid alone has them)");
  CoupledState<dim> state;
  state.has_fluid = fluid.has_value();
  state.has_sediment = sediment.has_value();
  if (fluid) state.fluid = mpm::initial_state(settings);
  if (sediment) {
    state.sediment = mpm::initial_state(settings);
    // A continuum sediment is a solid: its grains carry F and the plastic state.
    if (!sediment->materials.empty()) mpm::solid::add_solid_channels(state.sediment.particles);
  }
  if (!(fluid && sediment)) drag.reset();
  return {std::move(settings), std::move(colliders), fluid, std::move(pressure), std::move(sediment), drag,
          std::move(state), {}, {}, {}};
}

template <int dim>
void add_fluid_particles(CoupledScene<dim>& scene, const std::vector<mpm::Vec<dim>>& positions, double volume,
                         double fluid_fraction, const mpm::Vec<dim>& velocity, const std::string& where) {
  mpm::verify<mpm::InputError>(scene.fluid.has_value(), where + ": the scene has no fluid phase");
  mpm::verify<mpm::InputError>(
      fluid_fraction > 0.0 && fluid_fraction <= 1.0,
      where + ": fluid fraction " + std::to_string(fluid_fraction) + " outside (0, 1]");
  if (const std::string why = mpm::first_outside_domain(scene.settings, positions).why; !why.empty())
    throw mpm::InputError(where + ": " + why);
  const double mass = fluid_fraction * scene.fluid->density * volume;
  for (const mpm::Vec<dim>& x : positions)
    scene.state.fluid.particles.push_back(x, velocity, mass, volume, 0);
}

template <int dim>
void add_sediment_particles(CoupledScene<dim>& scene, const std::vector<mpm::Vec<dim>>& positions,
                            double grain_volume, const mpm::Vec<dim>& velocity, const std::string& where) {
  mpm::verify<mpm::InputError>(scene.sediment.has_value(), where + ": the scene has no sediment phase");
  if (const std::string why = mpm::first_outside_domain(scene.settings, positions).why; !why.empty())
    throw mpm::InputError(where + ": " + why);
  const double mass = scene.sediment->density * grain_volume;
  const std::uint16_t material = scene.sediment->materials.empty() ? discrete_grain : 0;
  for (const mpm::Vec<dim>& x : positions)
    scene.state.sediment.particles.push_back(x, velocity, mass, grain_volume, material);
}

template <int dim>
mpm::Pipeline<CoupledState<dim>> make_coupled_pipeline(const CoupledScene<dim>& scene) {
  namespace ms = mpm::stages;
  using stages::OnPhase;
  using stages::Phase;
  const bool wet = scene.fluid.has_value(), sandy = scene.sediment.has_value();
  const bool continuum = sandy && !scene.sediment->materials.empty();
  const bool switching = continuum && scene.sediment->switching.has_value();

  // Free fall as a wave speed (fluid_scene.h) for both phases; a continuum sediment adds its
  // elastic wave speed.
  typename stages::CoupledTimeStep<dim>::Settings dt;
  dt.cfl = scene.settings.cfl;
  dt.wave_cfl = scene.settings.wave_cfl;
  dt.max_dt = scene.settings.max_dt;
  dt.wave_speed = std::sqrt(scene.settings.gravity.norm() * scene.settings.dx);
  for (const auto& c : scene.colliders.colliders())
    dt.wave_speed = std::max(dt.wave_speed, c.velocity().norm());
  typename stages::CoupledTimeStep<dim>::Settings dt_sediment = dt;
  if (continuum)
    for (const auto& m : scene.sediment->materials)
      dt_sediment.wave_speed = std::max(dt_sediment.wave_speed, m.wave_speed());

  std::vector<std::string> initial;
  for (const auto& [present, phase, particles] :
       {std::tuple{wet, std::string("fluid."), &scene.state.fluid.particles},
        std::tuple{sandy, std::string("sediment."), &scene.state.sediment.particles}})
    if (present)
      for (const std::string& f : mpm::particle_fields(*particles)) initial.push_back(phase + f);
  mpm::Pipeline<CoupledState<dim>> p(initial);

  auto on = [&](Phase phase, auto stage) { p.add(std::make_unique<OnPhase<dim>>(phase, std::move(stage))); };
  auto both = [&](auto make) {
    if (wet) on(Phase::fluid, make());
    if (sandy) on(Phase::sediment, make());
  };
  p.add(std::make_unique<stages::CoupledTimeStep<dim>>(dt, dt_sediment));
  // Outflow (both phases), then the emitters, before the sort that rebuilds the buckets.
  if (const auto regions = mpm::geometry::flow_sink_regions(scene.flow, scene.settings); !regions.empty())
    both([&] { return std::make_unique<ms::ParticleSink<dim>>(regions); });
  for (const auto& source : scene.fluid_sources) on(Phase::fluid, std::make_unique<ms::ParticleSource<dim>>(source));
  for (const auto& source : scene.sediment_sources)
    on(Phase::sediment, std::make_unique<ms::ParticleSource<dim>>(source));
  both([] { return std::make_unique<ms::SortParticles<dim>>(); });
  both([] { return std::make_unique<ms::ParticlesToGrid<dim>>(); });
  if (wet && sandy)
    p.add(std::make_unique<stages::VolumeFractionStage<dim>>(scene.fluid->density, scene.sediment->density,
                                                             scene.sediment->min_fluid_fraction));
  if (continuum)
    on(Phase::sediment, std::make_unique<ms::StressForces<dim>>(scene.sediment->materials, switching));
  if (wet) on(Phase::fluid, std::make_unique<ms::GridVelocityUpdate<dim>>(false));
  if (sandy) on(Phase::sediment, std::make_unique<ms::GridVelocityUpdate<dim>>(continuum));
  if (wet && scene.fluid->viscosity > 0.0)
    on(Phase::fluid, std::make_unique<fluid::stages::ImplicitViscosity<dim>>(
                         scene.fluid->viscosity / scene.fluid->density, scene.colliders,
                         fluid::SolveControl{1e-10, 0.0, 1000}));
  if (wet && sandy) p.add(std::make_unique<stages::ExchangeStage<dim>>(*scene.drag));
  both([&] { return std::make_unique<ms::GridBoundary<dim>>(scene.colliders); });
  if (wet && sandy) {
    p.add(std::make_unique<stages::MixtureProjection<dim>>(scene.fluid->density, scene.sediment->density,
                                                           *scene.drag, scene.colliders, scene.pressure));
    // The sediment correction reaches nodes next to walls that the fluid's prescribed
    // nodes do not shield: impose the sediment's wall conditions again.
    on(Phase::sediment, std::make_unique<ms::GridBoundary<dim>>(scene.colliders));
  } else if (wet) {
    on(Phase::fluid, std::make_unique<fluid::stages::PressureProjection<dim>>(
                         scene.fluid->density, scene.colliders, scene.pressure));
  }
  if (continuum) {
    on(Phase::sediment, std::make_unique<ms::DeformationUpdate<dim>>());
    if (ms::any_plastic(scene.sediment->materials))
      on(Phase::sediment, std::make_unique<ms::ReturnMap<dim>>(scene.sediment->materials));
  }
  both([] { return std::make_unique<ms::GridToParticles<dim>>(); });
  if (switching)
    p.add(std::make_unique<stages::ReclassifySediment<dim>>(*scene.sediment->switching, scene.sediment->density,
                                                            0, wet));
  return p;
}

template <int dim>
void advance(CoupledState<dim>& state, mpm::Pipeline<CoupledState<dim>>& pipeline, double t_end,
             int max_steps) {
  for (int n = 0; state.time < t_end; ++n) {
    if (n >= max_steps) {
      std::ostringstream why;
      why << "coupled step: " << max_steps << " steps did not reach t = " << t_end << " s (t = " << state.time
          << " s, dt = " << state.dt << " s)";
      throw mpm::NumericalError(why.str());
    }
    state.dt_limit = t_end - state.time;
    pipeline.step(state);
    state.time = state.dt >= state.dt_limit ? t_end : state.time + state.dt;
    ++state.step;
  }
}

#define COUPLED_SCENE(dim)                                                                                 \
  template CoupledScene<dim> make_coupled_scene(                                                           \
      mpm::SceneSettings<dim>, mpm::geometry::ColliderSet<dim>, std::optional<fluid::FluidMaterial>,       \
      fluid::stages::PressureSettings, std::optional<SedimentPhase<dim>>, std::optional<drag::DragLaw>);   \
  template void add_fluid_particles(CoupledScene<dim>&, const std::vector<mpm::Vec<dim>>&, double, double, \
                                    const mpm::Vec<dim>&, const std::string&);                             \
  template void add_sediment_particles(CoupledScene<dim>&, const std::vector<mpm::Vec<dim>>&, double,      \
                                       const mpm::Vec<dim>&, const std::string&);                          \
  template mpm::Pipeline<CoupledState<dim>> make_coupled_pipeline(const CoupledScene<dim>&);               \
  template void advance(CoupledState<dim>&, mpm::Pipeline<CoupledState<dim>>&, double, int);
COUPLED_SCENE(2)
COUPLED_SCENE(3)

}  // namespace coupling
