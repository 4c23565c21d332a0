#pragma once
//! Assembles a free-surface LANS fluid scene from a scene file:
//!   time_step -> [sink -> source] -> sort -> p2g -> [solver grid update] -> boundary
//!   -> [solver projection] -> [solver particle update] -> g2p (and advection)
//! which for the default solver (fluid.solver: projection, solver/projection_solver.h) reads
//!   ... p2g -> grid_update (gravity) -> viscosity (only when mu > 0) -> boundary -> pressure -> g2p
//! with periodic_fold after p2g, periodic_fill before g2p and periodic_wrap after it when the
//! scene has a periodic axis (mpm/core/stages/periodic_boundary.h).
//! The projection leaves every node that a wall or collider prescribes untouched, so the
//! boundary conditions still hold after it and no second boundary stage is needed.
//!
//!   fluid:                   # the liquid
//!     density: 1000          # rho_w [kg/m^3] > 0
//!     viscosity: 1.0e-3      # dynamic viscosity mu [Pa s] >= 0 (0: inviscid, no viscosity stage)
//!     solver: projection     # one of fluid_solver_names()
//!   pressure:                # optional
//!     solver: mgpcg          # one of pressure_solver_names()
//!     tolerance: 1.0e-8      # relative residual |b - A p| / |b|, in (0, 1)
//!     max_iterations: 1000
//!     on_failure: stop       # stop | warn: what a solve that misses the tolerance does
//!   bodies:                  # fluid regions: {shape: box, lo, hi} or {shape: sphere, center,
//!                            # radius}; optional particles_per_cell (k^dim), jitter, seed, velocity
//!     - {shape: box, lo: [0, 0], hi: [0.1, 0.2], particles_per_cell: 4, velocity: [0, 0]}
//! plus the shared keys (scene_settings.h), walls/colliders (collider_config.h) and the optional
//! inflow/outflow (flow_boundary_config.h): the sink and source stages exist only with them. Walls act
//! on the fluid as prescribed node velocities: `sticky` holds every component of a node inside
//! the wall, `slip` and `separate` the normal one, and the pressure moves the tangential one
//! (pressure_projection.cpp). The scene files use sticky walls; an obstacle a few cells across
//! in a current slips, since sticky nodes would hold a cell of dead water around it (user
//! guide 4.16).
#include <fluid/solver/fluid_solver.h>
#include <fluid/stages/pressure_projection.h>

#include <mpm/core/config.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/runner.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>
#include <mpm/geometry/flow_boundary_config.h>

#include <memory>
#include <string>
#include <vector>

namespace fluid {

template <int dim>
struct FluidScene {
  mpm::SceneSettings<dim> settings;
  FluidMaterial fluid;
  stages::PressureSettings pressure;
  mpm::geometry::ColliderSet<dim> colliders;
  std::shared_ptr<const FluidSolver<dim>> solver;  //!< fluid.solver (fluid_solver.h)
  mpm::MpmState<dim> state;                 //!< particles seeded (with the solver's channels), grid sized to the domain
  mpm::geometry::FlowBoundaries<dim> flow;  //!< inflow/outflow (already applied to `colliders`)
};

//! The `fluid` map: density > 0, viscosity >= 0.
FluidMaterial parse_fluid_material(const mpm::Config& fluid);
//! `solver` of the `fluid` map (one of fluid_solver_names(), default "projection") and the keys
//! of that solver: weakly_compressible reads speed_of_sound (c [m/s] > 0, default 20) and
//! eos_exponent (gamma >= 1, default 7).
FluidSolverSettings parse_fluid_solver(const mpm::Config& fluid);
//! The optional `pressure` map of `scene` (defaults: mgpcg, 1e-8, 1000 iterations, stop).
stages::PressureSettings parse_pressure_settings(const mpm::Config& scene);

//! A scene with no particles, the grid sized to the settings' domain and the fluid solver called
//! `solver` (fluid_solver_names()).
template <int dim>
FluidScene<dim> make_fluid_scene(mpm::SceneSettings<dim> settings, FluidMaterial fluid,
                                 stages::PressureSettings pressure, mpm::geometry::ColliderSet<dim> colliders,
                                 const FluidSolverSettings& solver = {});

//! Appends fluid particles of volume `volume` [m^dim] each at `positions`, moving with
//! `velocity`; InputError naming `where` when one lies outside the domain.
template <int dim>
void add_fluid_particles(FluidScene<dim>& scene, const std::vector<Vec<dim>>& positions, double volume,
                         const Vec<dim>& velocity, const std::string& where);

//! Seeds the optional `bodies` list of `scene` (box and sphere shapes).
template <int dim>
void seed_fluid_bodies(FluidScene<dim>& fluid, const mpm::Config& scene);

//! Reads settings, the fluid, the pressure keys, walls/colliders, inflow/outflow and bodies.
template <int dim>
FluidScene<dim> load_fluid_scene(const mpm::Config& scene);

//! The fluid pipeline of the header comment for `scene` and its solver; besides the particle
//! CFL, dt <= wave_cfl dx / c with c the solver's wave_speed().
template <int dim>
mpm::Pipeline<mpm::MpmState<dim>> make_fluid_pipeline(const FluidScene<dim>& scene);

}  // namespace fluid
