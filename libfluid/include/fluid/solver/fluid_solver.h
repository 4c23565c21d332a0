#pragma once
//! The fluid-step interface: what a fluid solver adds to a step, so that a fluid scene and the
//! liquid of a coupled scene assemble their pipelines from the same solver and a scene can
//! swap it (`fluid.solver:`). A fluid pipeline runs
//!   time_step -> sort -> p2g -> grid_update() -> boundary -> projection() -> particle_update()
//!   -> g2p
//! (with the periodic and inflow/outflow stages of fluid_scene.h around them). In a coupled
//! scene with a sediment an incompressible solver's projection() is replaced by the mixture
//! projection of libcoupling, which solves the same constraint for both phases.
#include <mpm/core/particles.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <fluid/stages/pressure_projection.h>

#include <memory>
#include <string>
#include <vector>

namespace fluid {

struct FluidMaterial {
  double density = 1000.0;  //!< rho_w [kg/m^3]
  double viscosity = 0.0;   //!< dynamic viscosity mu [Pa s]
};

//! The `solver` of a `fluid` map and the keys only that solver reads.
struct FluidSolverSettings {
  std::string name = "projection";  //!< one of fluid_solver_names()
  double speed_of_sound = 20.0;     //!< weakly_compressible: c [m/s] (equation_of_state.h)
  double eos_exponent = 7.0;        //!< weakly_compressible: gamma of the Tait equation
  bool hydrostatic_start = true;    //!< weakly_compressible: start_at_rest compresses to equilibrium
};

template <int dim>
class FluidSolver {
public:
  using Stages = std::vector<std::unique_ptr<mpm::Stage<mpm::MpmState<dim>>>>;
  virtual ~FluidSolver() = default;
  virtual std::string name() const = 0;
  //! Whether the solver keeps div v = 0 (the mixture projection of a coupled scene can stand in
  //! for its projection()).
  virtual bool incompressible() const = 0;
  //! Gives `particles` the channels the solver's stages read (idempotent).
  virtual void add_channels(mpm::Particles<dim>& particles) const = 0;
  //! Puts the seeded liquid at rest under gravity into the solver's equilibrium, once, before the
  //! first step (not on a restart: the checkpoint holds the state). Only a solver whose
  //! pressure is particle state needs it (the weakly compressible liquid's J).
  virtual void start_at_rest(mpm::Particles<dim>& /*particles*/, const mpm::SceneSettings<dim>& /*settings*/) const {}
  //! The fastest signal the explicit part must resolve [m/s] (dt <= wave_cfl dx / c).
  virtual double wave_speed() const = 0;
  //! From the transferred momentum to the velocity before the boundary conditions.
  virtual Stages grid_update() const = 0;
  //! After the boundary conditions: what makes the velocity admissible (the pressure projection).
  virtual Stages projection() const = 0;
  //! From the final grid velocity to the particle state that g2p completes.
  virtual Stages particle_update() const = 0;
};

//! "projection": the incompressible LANS step (projection_solver.h); "weakly_compressible": the
//! pressure from each particle's volume by an equation of state (weakly_compressible_solver.h).
std::vector<std::string> fluid_solver_names();

//! The solver `solver.name` (one of fluid_solver_names()); `colliders` are the obstacles the
//! boundary stage applies, `settings` the scene's (dx, gravity). InputError for another name.
template <int dim>
std::shared_ptr<const FluidSolver<dim>> make_fluid_solver(const FluidSolverSettings& solver, const FluidMaterial& fluid,
                                                          const stages::PressureSettings& pressure,
                                                          const mpm::geometry::ColliderSet<dim>& colliders,
                                                          const mpm::SceneSettings<dim>& settings);

//! Appends the implicit viscosity stage to `stages` when the fluid is viscous (mu > 0), with the
//! Dirichlet velocities of `colliders`: every solver's grid update ends with it.
template <int dim>
void append_viscosity(typename FluidSolver<dim>::Stages& stages, const FluidMaterial& fluid,
                      const mpm::geometry::ColliderSet<dim>& colliders);

//! The speed that limits the time step of a free surface: sqrt(|g| dx), so that dt <= wave_cfl
//! sqrt(dx / |g|) (a particle starting from rest falls less than wave_cfl^2 dx / 2 in one step),
//! or a faster moving collider (a cavity lid drags the liquid next to it at its speed).
template <int dim>
double free_surface_wave_speed(const mpm::SceneSettings<dim>& settings,
                               const mpm::geometry::ColliderSet<dim>& colliders);

}  // namespace fluid
