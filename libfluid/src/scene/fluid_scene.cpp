#include <fluid/scene/fluid_scene.h>

#include <mpm/core/error.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/periodic_boundary.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/core/stages/time_step_control.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>

namespace fluid {

using mpm::Config;
using mpm::Range;

FluidMaterial parse_fluid_material(const Config& fluid) {
  FluidMaterial m;
  m.density = fluid.number("density", Range::positive());
  m.viscosity = fluid.number("viscosity", 0.0, Range::non_negative());
  return m;
}

FluidSolverSettings parse_fluid_solver(const Config& fluid) {
  FluidSolverSettings s;
  s.name = fluid.choice("solver", s.name, fluid_solver_names());
  if (s.name == "weakly_compressible") {
    s.speed_of_sound = fluid.number("speed_of_sound", s.speed_of_sound, Range::positive());
    s.eos_exponent = fluid.number("eos_exponent", s.eos_exponent, Range::closed(1.0, 100.0));
    s.hydrostatic_start = fluid.choice("initial_pressure", "hydrostatic", {"hydrostatic", "zero"}) == "hydrostatic";
  }
  return s;
}

stages::PressureSettings parse_pressure_settings(const Config& scene) {
  stages::PressureSettings s;
  const std::optional<Config> p = scene.optional_child("pressure");
  if (!p) return s;
  s.solver = p->choice("solver", s.solver, pressure_solver_names());
  std::vector<std::string> fallbacks = pressure_solver_names();
  fallbacks.push_back("none");
  if (const std::string fallback = p->choice("fallback", "none", fallbacks); fallback != "none") s.fallback = fallback;
  s.control.relative_tolerance = p->number("tolerance", s.control.relative_tolerance, Range::open(0.0, 1.0));
  s.control.max_iterations = p->integer("max_iterations", s.control.max_iterations, 1, 1000000);
  s.setup_reuse = p->integer("setup_reuse", s.setup_reuse, 1, 1000);
  s.on_failure =
      p->choice("on_failure", "stop", {"stop", "warn"}) == "stop" ? stages::OnFailure::stop : stages::OnFailure::warn;
  s.surface_extension = p->flag("surface_extension", s.surface_extension);
  return s;
}

template <int dim>
FluidScene<dim> make_fluid_scene(mpm::SceneSettings<dim> settings, FluidMaterial fluid,
                                 stages::PressureSettings pressure, mpm::geometry::ColliderSet<dim> colliders,
                                 const FluidSolverSettings& solver) {
  mpm::MpmState<dim> state = mpm::initial_state(settings);
  std::shared_ptr<const FluidSolver<dim>> s = make_fluid_solver<dim>(solver, fluid, pressure, colliders, settings);
  // periodic_fold folds mass and momentum before the solver's grid update, so forces that a
  // solver scatters onto ghost nodes would be lost: a periodic axis needs the projection.
  const bool periodic = std::any_of(settings.periodic.begin(), settings.periodic.end(), [](bool p) { return p; });
  MPM_VERIFY(!periodic || s->incompressible(), mpm::InputError,
             "fluid solver '" + solver.name + "' has no periodic axes (its pressure forces are not folded); use " +
                 "fluid.solver: projection");
  s->add_channels(state.particles);
  return {std::move(settings), fluid, std::move(pressure), std::move(colliders), std::move(s), std::move(state), {}};
}

template <int dim>
void add_fluid_particles(FluidScene<dim>& scene, const std::vector<Vec<dim>>& positions, double volume,
                         const Vec<dim>& velocity, const std::string& where) {
  if (const std::string why = mpm::first_outside_domain(scene.settings, positions).why; !why.empty())
    throw mpm::InputError(where + ": " + why);
  const double mass = scene.fluid.density * volume;
  scene.state.particles.reserve_more(positions.size());
  for (const Vec<dim>& x : positions) scene.state.particles.push_back(x, velocity, mass, volume, 0);
}

template <int dim>
void seed_fluid_bodies(FluidScene<dim>& fluid, const Config& scene) {
  for (const Config& body : scene.list("bodies")) {
    const mpm::geometry::BodyParticles<dim> b = mpm::geometry::seed_body_shape<dim>(body, fluid.settings);
    add_fluid_particles(fluid, b.x, b.volume, body.vector<dim>("velocity", Vec<dim>::Zero()), body.path());
  }
}

template <int dim>
FluidScene<dim> load_fluid_scene(const Config& scene) {
  mpm::SceneSettings<dim> settings = mpm::parse_scene_settings<dim>(scene);
  auto colliders = mpm::geometry::parse_colliders<dim>(scene, settings.domain_lo, settings.domain_hi,
                                                       mpm::wall_layer(settings.kernel, settings.dx));
  mpm::geometry::FlowBoundaries<dim> flow = mpm::geometry::parse_flow_boundaries<dim>(scene, settings);
  mpm::geometry::add_flow_boundaries(flow, colliders);
  const Config fluid = scene.child("fluid");
  FluidScene<dim> s = make_fluid_scene(std::move(settings), parse_fluid_material(fluid), parse_pressure_settings(scene),
                                       std::move(colliders), parse_fluid_solver(fluid));
  s.flow = std::move(flow);
  seed_fluid_bodies(s, scene);
  s.solver->start_at_rest(s.state.particles, s.settings);
  return s;
}

template <int dim>
mpm::Pipeline<mpm::MpmState<dim>> make_fluid_pipeline(const FluidScene<dim>& scene) {
  namespace ms = mpm::stages;
  mpm::Pipeline<mpm::MpmState<dim>> p(mpm::particle_fields(scene.state.particles));
  p.add(std::make_unique<ms::TimeStepControl<dim>>(ms::time_step_settings(scene.settings, scene.solver->wave_speed())));
  // Outflow, then inflow, before the sort that rebuilds the buckets.
  if (auto regions = mpm::geometry::flow_sink_regions(scene.flow, scene.settings); !regions.empty())
    p.add(std::make_unique<ms::ParticleSink<dim>>(std::move(regions)));
  if (scene.flow.inflow)
    p.add(std::make_unique<ms::ParticleSource<dim>>(
        mpm::geometry::inflow_source(*scene.flow.inflow, scene.settings, scene.fluid.density)));
  p.add(std::make_unique<ms::SortParticles<dim>>());
  p.add(std::make_unique<ms::ParticlesToGrid<dim>>());
  const bool periodic = scene.state.grid.is_periodic();
  if (periodic) p.add(std::make_unique<ms::PeriodicFold<dim>>());
  for (auto& stage : scene.solver->grid_update()) p.add(std::move(stage));
  p.add(std::make_unique<ms::GridBoundary<dim>>(scene.colliders));
  for (auto& stage : scene.solver->projection()) p.add(std::move(stage));
  if (periodic) p.add(std::make_unique<ms::PeriodicFill<dim>>());
  for (auto& stage : scene.solver->particle_update()) p.add(std::move(stage));
  p.add(std::make_unique<ms::GridToParticles<dim>>());
  if (periodic) p.add(std::make_unique<ms::PeriodicWrap<dim>>());
  return p;
}

#define FLUID_SCENE(dim)                                                                                      \
  template FluidScene<dim> make_fluid_scene(mpm::SceneSettings<dim>, FluidMaterial, stages::PressureSettings, \
                                            mpm::geometry::ColliderSet<dim>, const FluidSolverSettings&);     \
  template void add_fluid_particles(FluidScene<dim>&, const std::vector<Vec<dim>>&, double, const Vec<dim>&,  \
                                    const std::string&);                                                      \
  template void seed_fluid_bodies(FluidScene<dim>&, const Config&);                                           \
  template FluidScene<dim> load_fluid_scene<dim>(const Config&);                                              \
  template mpm::Pipeline<mpm::MpmState<dim>> make_fluid_pipeline(const FluidScene<dim>&);
FLUID_SCENE(2)
FLUID_SCENE(3)

}  // namespace fluid
