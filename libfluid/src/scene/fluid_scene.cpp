#include <fluid/scene/fluid_scene.h>
#include <fluid/stages/implicit_viscosity.h>

#include <mpm/core/error.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/core/stages/time_step_control.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace fluid {

using mpm::Config;
using mpm::Range;

FluidMaterial parse_fluid_material(const Config& fluid) {
  FluidMaterial m;
  m.density = fluid.number("density", Range::positive());
  m.viscosity = fluid.number("viscosity", 0.0, Range::non_negative());
  return m;
}

stages::PressureSettings parse_pressure_settings(const Config& scene) {
  stages::PressureSettings s;
  const std::optional<Config> p = scene.optional_child("pressure");
  if (!p) return s;
  s.solver = p->choice("solver", s.solver, pressure_solver_names());
  s.control.relative_tolerance = p->number("tolerance", s.control.relative_tolerance, Range::open(0.0, 1.0));
  s.control.max_iterations = p->integer("max_iterations", s.control.max_iterations, 1, 1000000);
  s.on_failure = p->choice("on_failure", "stop", {"stop", "warn"}) == "stop" ? stages::OnFailure::stop
                                                                              : stages::OnFailure::warn;
  return s;
}

template <int dim>
FluidScene<dim> make_fluid_scene(mpm::SceneSettings<dim> settings, FluidMaterial fluid,
                                 stages::PressureSettings pressure, mpm::geometry::ColliderSet<dim> colliders) {
  FluidScene<dim> s{std::move(settings), fluid, std::move(pressure), std::move(colliders), {}};
  s.state.grid = mpm::SparseGrid<dim>(s.settings.domain_lo, s.settings.domain_hi, s.settings.dx);
  s.state.kernel = s.settings.kernel;
  s.state.transfer = s.settings.transfer;
  s.state.gravity = s.settings.gravity;
  return s;
}

namespace {
template <int dim>
std::string point_text(const Vec<dim>& x) {
  std::ostringstream s;
  s << "(";
  for (int a = 0; a < dim; ++a) s << (a ? ", " : "") << x[a];
  s << ")";
  return s.str();
}

//! Why the first position outside the domain is outside ("" when all are inside).
template <int dim>
std::string first_outside(const mpm::SceneSettings<dim>& settings, const std::vector<Vec<dim>>& positions) {
  for (const Vec<dim>& x : positions)
    for (int a = 0; a < dim; ++a)
      if (!(x[a] >= settings.domain_lo[a] && x[a] <= settings.domain_hi[a]))
        return "a particle at " + point_text<dim>(x) + " lies outside the domain " +
               point_text<dim>(settings.domain_lo) + " - " + point_text<dim>(settings.domain_hi);
  return "";
}
}  // namespace

template <int dim>
void add_fluid_particles(FluidScene<dim>& scene, const std::vector<Vec<dim>>& positions, double volume,
                         const Vec<dim>& velocity, const std::string& where) {
  if (const std::string why = first_outside(scene.settings, positions); !why.empty())
    throw mpm::InputError(where + ": " + why);
  const double mass = scene.fluid.density * volume;
  for (const Vec<dim>& x : positions) scene.state.particles.push_back(x, velocity, mass, volume, 0);
}

template <int dim>
void seed_fluid_bodies(FluidScene<dim>& fluid, const Config& scene) {
  const double dx = fluid.settings.dx;
  for (const Config& body : scene.list("bodies")) {
    const int ppc = body.integer("particles_per_cell", dim == 2 ? 4 : 8, 1, 1000);
    const double jitter = body.number("jitter", 0.0, Range::half_open(0.0, 1.0));
    const auto seed = static_cast<std::uint64_t>(body.integer("seed", 1, 0, 1 << 30));
    const Vec<dim> velocity = body.vector<dim>("velocity", Vec<dim>::Zero());
    const std::string shape = body.choice("shape", "box", {"box", "sphere"});
    std::vector<Vec<dim>> x;
    try {
      if (shape == "box")
        x = mpm::geometry::seed_box<dim>(body.vector<dim>("lo"), body.vector<dim>("hi"), dx, ppc, jitter, seed);
      else
        x = mpm::geometry::seed_sphere<dim>(body.vector<dim>("center"), body.number("radius", Range::positive()),
                                            dx, ppc, jitter, seed);
    } catch (const mpm::InputError& e) {
      body.fail("particles_per_cell", e.what());
    }
    if (x.empty()) body.fail("shape", "the body contains no particle at this resolution");
    if (const std::string why = first_outside(fluid.settings, x); !why.empty())
      body.fail(shape == "box" ? "hi" : "center", "expected the body inside the domain, but " + why);
    add_fluid_particles(fluid, x, mpm::geometry::particle_volume<dim>(dx, ppc), velocity, body.path());
  }
}

template <int dim>
FluidScene<dim> load_fluid_scene(const Config& scene) {
  mpm::SceneSettings<dim> settings = mpm::parse_scene_settings<dim>(scene);
  auto colliders = mpm::geometry::parse_colliders<dim>(scene, settings.domain_lo, settings.domain_hi,
                                                        mpm::wall_layer(settings.kernel, settings.dx));
  FluidScene<dim> s = make_fluid_scene(std::move(settings), parse_fluid_material(scene.child("fluid")),
                                       parse_pressure_settings(scene), std::move(colliders));
  seed_fluid_bodies(s, scene);
  return s;
}

template <int dim>
mpm::Pipeline<mpm::MpmState<dim>> make_fluid_pipeline(const FluidScene<dim>& scene) {
  namespace ms = mpm::stages;
  typename ms::TimeStepControl<dim>::Settings dt;
  dt.cfl = scene.settings.cfl;
  dt.wave_cfl = scene.settings.wave_cfl;
  dt.max_dt = scene.settings.max_dt;
  // The free-fall limit as a "wave speed": wave_cfl dx / sqrt(|g| dx) = wave_cfl sqrt(dx / |g|);
  // and moving obstacles (a cavity lid) drag the liquid next to them at their speed.
  dt.wave_speed = std::sqrt(scene.settings.gravity.norm() * scene.settings.dx);
  for (const auto& c : scene.colliders.colliders()) dt.wave_speed = std::max(dt.wave_speed, c.velocity().norm());

  mpm::Pipeline<mpm::MpmState<dim>> p({"particle.x", "particle.v", "particle.C", "particle.mass",
                                       "particle.volume0", "particle.material"});
  p.add(std::make_unique<ms::TimeStepControl<dim>>(dt));
  p.add(std::make_unique<ms::SortParticles<dim>>());
  p.add(std::make_unique<ms::ParticlesToGrid<dim>>());
  p.add(std::make_unique<ms::GridVelocityUpdate<dim>>(false));
  if (scene.fluid.viscosity > 0.0)
    p.add(std::make_unique<stages::ImplicitViscosity<dim>>(scene.fluid.viscosity / scene.fluid.density,
                                                           scene.colliders, SolveControl{1e-10, 0.0, 1000}));
  p.add(std::make_unique<ms::GridBoundary<dim>>(scene.colliders));
  p.add(std::make_unique<stages::PressureProjection<dim>>(scene.fluid.density, scene.colliders, scene.pressure));
  p.add(std::make_unique<ms::GridToParticles<dim>>());
  return p;
}

template <int dim>
void add_pressure_columns(mpm::Runner<dim>& runner, mpm::Pipeline<mpm::MpmState<dim>>& pipeline) {
  const auto* projection = pipeline.template find<stages::PressureProjection<dim>>();
  if (!projection) throw mpm::InputError("add_pressure_columns: the pipeline has no pressure stage");
  runner.add_column("pressure_iterations",
                    [projection](const mpm::MpmState<dim>&) { return double(projection->last_result().iterations); });
  runner.add_column("pressure_residual",
                    [projection](const mpm::MpmState<dim>&) { return projection->last_result().relative_residual; });
}

#define FLUID_SCENE(dim)                                                                                   \
  template FluidScene<dim> make_fluid_scene(mpm::SceneSettings<dim>, FluidMaterial, stages::PressureSettings, \
                                            mpm::geometry::ColliderSet<dim>);                              \
  template void add_fluid_particles(FluidScene<dim>&, const std::vector<Vec<dim>>&, double, const Vec<dim>&, \
                                    const std::string&);                                                   \
  template void seed_fluid_bodies(FluidScene<dim>&, const Config&);                                        \
  template FluidScene<dim> load_fluid_scene<dim>(const Config&);                                           \
  template mpm::Pipeline<mpm::MpmState<dim>> make_fluid_pipeline(const FluidScene<dim>&);                  \
  template void add_pressure_columns(mpm::Runner<dim>&, mpm::Pipeline<mpm::MpmState<dim>>&);
FLUID_SCENE(2)
FLUID_SCENE(3)

}  // namespace fluid
