#include <coupling/coupled_scene.h>
#include <coupling/stages/bed_load.h>
#include <coupling/stages/coupled_time_step.h>
#include <coupling/stages/exchange_stage.h>
#include <coupling/stages/hold_sediment.h>
#include <coupling/stages/mixture_projection.h>
#include <coupling/stages/on_phase.h>
#include <coupling/stages/pore_pressure.h>
#include <coupling/stages/volume_fraction_stage.h>
#include <fluid/stages/equation_of_state.h>
#include <fluid/stages/surface_velocity_extension.h>
#include <mpm/core/error.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/core/stages/time_step_control.h>

#include <algorithm>
#include <tuple>

namespace coupling {

namespace {
// The obstacles with the sediment's own contacts (SedimentPhase::contacts) where it has them.
template <int dim>
mpm::geometry::ColliderSet<dim> with_contacts(const mpm::geometry::ColliderSet<dim>& colliders,
                                              const std::vector<std::optional<mpm::geometry::Contact>>& contacts) {
  mpm::verify<mpm::InputError>(contacts.size() <= colliders.colliders().size(),
                               "coupled scene: more sediment contacts than colliders");
  mpm::geometry::ColliderSet<dim> out;
  for (std::size_t i = 0; i < colliders.colliders().size(); ++i) {
    mpm::geometry::Collider<dim> c = colliders.colliders()[i];
    if (i < contacts.size() && contacts[i]) c.set_contact(*contacts[i]);
    out.add(std::move(c));
  }
  if (colliders.walls()) out.set_walls(*colliders.walls());
  return out;
}
}  // namespace

template <int dim>
CoupledScene<dim> make_coupled_scene(mpm::SceneSettings<dim> settings, mpm::geometry::ColliderSet<dim> colliders,
                                     std::optional<fluid::FluidMaterial> fluid,
                                     fluid::stages::PressureSettings pressure,
                                     std::optional<SedimentPhase<dim>> sediment, std::optional<drag::DragLaw> drag,
                                     const fluid::FluidSolverSettings& fluid_solver) {
  mpm::verify<mpm::InputError>(fluid || sediment, "coupled scene: neither a fluid nor a sediment phase");
  mpm::verify<mpm::InputError>(!(fluid && sediment) || drag.has_value(),
                               "coupled scene: a fluid and a sediment phase need a drag law");
  mpm::verify<mpm::InputError>(!sediment || !sediment->switching || !sediment->materials.empty(),
                               "coupled scene: continuum/discrete switching needs a sediment material");
  mpm::verify<mpm::InputError>(!sediment || sediment->solver != "grains" || sediment->materials.empty(),
                               "coupled scene: sediment solver 'grains' takes no material");
  // The volume fractions, the exchange and the mixture projection index nodes without the
  // periodic wrap of the fluid's own stages.
  for (int a = 0; a < dim; ++a)
    mpm::verify<mpm::InputError>(!settings.periodic[a], "coupled scene: no periodic axes (the fluid alone has them)");
  CoupledState<dim> state;
  state.has_fluid = fluid.has_value();
  state.has_sediment = sediment.has_value();
  std::shared_ptr<const fluid::FluidSolver<dim>> liquid;
  if (fluid) {
    state.fluid = mpm::initial_state(settings);
    liquid = fluid::make_fluid_solver<dim>(fluid_solver, *fluid, pressure, colliders, settings);
    liquid->add_channels(state.fluid.particles);
    if (sediment && !liquid->incompressible())  // its pressure from its own volume (pore_pressure.h)
      state.fluid.particles.template add_channel<double>(fluid::kLiquidVolumeRatio, 1.0, {.checkpoint = true});
  }
  std::shared_ptr<const mpm::solid::SolidSolver<dim>> solid;
  mpm::geometry::ColliderSet<dim> sediment_colliders =
      sediment ? with_contacts(colliders, sediment->contacts) : colliders;
  if (sediment) {
    state.sediment = mpm::initial_state(settings);
    solid = mpm::solid::make_solid_solver<dim>(sediment->solver, sediment->materials, sediment->switching.has_value(),
                                               sediment_colliders, sediment->implicit);
    solid->add_channels(state.sediment.particles);
  }
  if (!(fluid && sediment)) drag.reset();
  return {std::move(settings),
          std::move(colliders),
          std::move(sediment_colliders),
          fluid,
          std::move(pressure),
          std::move(sediment),
          drag,
          std::move(solid),
          std::move(liquid),
          std::move(state),
          {},
          {},
          {},
          {}};
}

template <int dim>
void add_fluid_particles(CoupledScene<dim>& scene, const std::vector<mpm::Vec<dim>>& positions, double volume,
                         double fluid_fraction, const mpm::Vec<dim>& velocity, const std::string& where) {
  mpm::verify<mpm::InputError>(scene.fluid.has_value(), where + ": the scene has no fluid phase");
  mpm::verify<mpm::InputError>(fluid_fraction > 0.0 && fluid_fraction <= 1.0,
                               where + ": fluid fraction " + std::to_string(fluid_fraction) + " outside (0, 1]");
  if (const std::string why = mpm::first_outside_domain(scene.settings, positions).why; !why.empty())
    throw mpm::InputError(where + ": " + why);
  const double mass = fluid_fraction * scene.fluid->density * volume;
  scene.state.fluid.particles.reserve_more(positions.size());
  for (const mpm::Vec<dim>& x : positions) scene.state.fluid.particles.push_back(x, velocity, mass, volume, 0);
}

template <int dim>
void add_sediment_particles(CoupledScene<dim>& scene, const std::vector<mpm::Vec<dim>>& positions, double grain_volume,
                            const mpm::Vec<dim>& velocity, const std::string& where) {
  mpm::verify<mpm::InputError>(scene.sediment.has_value(), where + ": the scene has no sediment phase");
  if (const std::string why = mpm::first_outside_domain(scene.settings, positions).why; !why.empty())
    throw mpm::InputError(where + ": " + why);
  const double mass = scene.sediment->density * grain_volume;
  const std::uint16_t material = scene.sediment->materials.empty() ? discrete_grain : 0;
  scene.state.sediment.particles.reserve_more(positions.size());
  for (const mpm::Vec<dim>& x : positions)
    scene.state.sediment.particles.push_back(x, velocity, mass, grain_volume, material);
}

template <int dim>
int vertical_axis(const mpm::SceneSettings<dim>& settings) {
  const mpm::Vec<dim>& g = settings.gravity;
  int up = -1;
  for (int a = 0; a < dim; ++a)
    if (g[a] != 0.0) up = up == -1 ? a : dim;
  mpm::verify<mpm::InputError>(up >= 0 && up < dim && g[up] < 0.0,
                               "coupled scene: a bed needs gravity along one axis, pointing down");
  return up;
}

template <int dim>
mpm::Pipeline<CoupledState<dim>> make_coupled_pipeline(const CoupledScene<dim>& scene) {
  namespace ms = mpm::stages;
  using stages::OnPhase;
  using stages::Phase;
  const bool wet = scene.fluid.has_value(), sandy = scene.sediment.has_value();
  // make_coupled_scene refused switching without a continuum material.
  const bool switching = sandy && scene.sediment->switching.has_value();

  // Each phase's solver limits its step; a sediment falls through a free surface too.
  const double free_surface = fluid::free_surface_wave_speed(scene.settings, scene.colliders);
  const auto dt = ms::time_step_settings(scene.settings, wet ? scene.fluid_solver->wave_speed() : free_surface);
  const auto dt_sediment =
      ms::time_step_settings(scene.settings, std::max(free_surface, sandy ? scene.solid_solver->wave_speed() : 0.0));

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
  if (wet) on(Phase::fluid, std::make_unique<ms::ParticlesToGrid<dim>>());
  if (sandy)  // p2g, with the stress forces in the same scatter where the solver has them
    for (auto& stage : scene.solid_solver->to_grid()) on(Phase::sediment, std::move(stage));
  // A liquid with an equation of state instead of the mixture projection (pore_pressure.h).
  const bool compressible = wet && sandy && !scene.fluid_solver->incompressible();
  if (wet && sandy)
    p.add(std::make_unique<stages::VolumeFractionStage<dim>>(scene.fluid->density, scene.sediment->density,
                                                             scene.sediment->min_fluid_fraction));
  if (wet)
    for (auto& stage : scene.fluid_solver->grid_update()) on(Phase::fluid, std::move(stage));
  if (sandy)
    for (auto& stage : scene.solid_solver->grid_update()) on(Phase::sediment, std::move(stage));
  if (compressible) p.add(std::make_unique<stages::PorePressureShare<dim>>());
  const bool bed_load = wet && sandy && scene.bed_load.has_value();
  if (bed_load)
    p.add(std::make_unique<stages::BedSurface<dim>>(*scene.bed_load, vertical_axis(scene.settings), scene.colliders));
  if (wet && sandy) p.add(std::make_unique<stages::ExchangeStage<dim>>(*scene.drag));
  if (bed_load) p.add(std::make_unique<stages::BedShear<dim>>());
  if (wet) on(Phase::fluid, std::make_unique<ms::GridBoundary<dim>>(scene.colliders));
  if (sandy) on(Phase::sediment, std::make_unique<ms::GridBoundary<dim>>(scene.sediment_colliders));
  if (wet && sandy && !compressible) {
    p.add(std::make_unique<stages::MixtureProjection<dim>>(scene.fluid->density, scene.sediment->density,
                                                           scene.colliders, scene.pressure));
    if (scene.pressure.surface_extension)
      on(Phase::fluid, std::make_unique<fluid::stages::SurfaceVelocityExtension<dim>>(scene.colliders));
    // The sediment correction reaches nodes next to walls that the fluid's prescribed
    // nodes do not shield: impose the sediment's wall conditions again.
    on(Phase::sediment, std::make_unique<ms::GridBoundary<dim>>(scene.sediment_colliders));
  } else if (wet) {  // a clear fluid's own projection (none for an equation of state)
    for (auto& stage : scene.fluid_solver->projection()) on(Phase::fluid, std::move(stage));
  }
  if (compressible) p.add(std::make_unique<stages::LiquidVolumeUpdate<dim>>());
  if (wet) {
    for (auto& stage : scene.fluid_solver->particle_update()) on(Phase::fluid, std::move(stage));
    on(Phase::fluid, std::make_unique<ms::GridToParticles<dim>>());
  }
  if (sandy && scene.sediment->hold_until > 0.0)
    p.add(std::make_unique<stages::HoldSediment<dim>>(scene.sediment->hold_until));
  if (sandy)  // g2p first, with the deformation update where the solver tracks F
    for (auto& stage : scene.solid_solver->particle_update()) on(Phase::sediment, std::move(stage));
  if (bed_load) p.add(std::make_unique<stages::BedLoadDrift<dim>>(scene.colliders));
  if (switching) {
    // With a bed-load closure a grain turns discrete only where its column's current suspends
    // it: u_* >= w_s / (kappa P_c), w_s the drag law's speed of one grain (stages/reclassify_sediment.h).
    std::optional<double> suspending_stress;
    if (bed_load) {
      const BedLoadLaw& law = *scene.bed_load;
      const double w_s = drag::terminal_velocity(*scene.drag, law.sediment_density, law.gravity);
      suspending_stress = law.suspending_stress(w_s, scene.sediment->switching->rouse_number);
    }
    p.add(std::make_unique<stages::ReclassifySediment<dim>>(*scene.sediment->switching, scene.sediment->density, 0, wet,
                                                            suspending_stress));
  }
  return p;
}

#define COUPLED_SCENE(dim)                                                                                            \
  template CoupledScene<dim> make_coupled_scene(mpm::SceneSettings<dim>, mpm::geometry::ColliderSet<dim>,             \
                                                std::optional<fluid::FluidMaterial>, fluid::stages::PressureSettings, \
                                                std::optional<SedimentPhase<dim>>, std::optional<drag::DragLaw>,      \
                                                const fluid::FluidSolverSettings&);                                   \
  template void add_fluid_particles(CoupledScene<dim>&, const std::vector<mpm::Vec<dim>>&, double, double,            \
                                    const mpm::Vec<dim>&, const std::string&);                                        \
  template void add_sediment_particles(CoupledScene<dim>&, const std::vector<mpm::Vec<dim>>&, double,                 \
                                       const mpm::Vec<dim>&, const std::string&);                                     \
  template mpm::Pipeline<CoupledState<dim>> make_coupled_pipeline(const CoupledScene<dim>&);                          \
  template int vertical_axis(const mpm::SceneSettings<dim>&);
COUPLED_SCENE(2)
COUPLED_SCENE(3)

}  // namespace coupling
