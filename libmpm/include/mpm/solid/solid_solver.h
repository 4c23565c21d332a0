#pragma once
//! The solid-step interface: what a solid solver adds to a step, so that a solid scene and the
//! sediment of a coupled scene assemble their pipelines from the same solver and a scene can
//! swap it (`solver:` in a solid scene, `sediment.solver:` in a coupled one). A pipeline runs
//!   time_step -> sort -> to_grid() -> grid_update() -> boundary -> particle_update()
//! (to_grid() is p2g, or p2g with what the solver scatters in the same pass; particle_update()
//! begins with g2p) and a coupled step puts the exchange and the mixture
//! projection between grid_update() and particle_update() (libcoupling). The implicit solver enforces walls and colliders inside its
//! grid update as well; the boundary stage after it then leaves its velocities unchanged.
#include <mpm/core/config.h>
#include <mpm/core/particles.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>
#include <mpm/solid/material.h>
#include <mpm/solid/stages/implicit_update.h>

#include <memory>
#include <string>
#include <vector>

namespace mpm::solid {

template <int dim>
class SolidSolver {
public:
  using Stages = std::vector<std::unique_ptr<Stage<MpmState<dim>>>>;
  virtual ~SolidSolver() = default;
  virtual std::string name() const = 0;
  //! Gives `particles` the channels the solver's stages read (idempotent).
  virtual void add_channels(Particles<dim>& particles) const = 0;
  //! The fastest wave the update must resolve [m/s] (the time step keeps dt <= wave_cfl dx / c);
  //! 0 when the update is stable at any step.
  virtual double wave_speed() const = 0;
  //! From the particles to the grid mass and momentum: p2g, unless the solver scatters more
  //! in the same pass (the explicit solver's stress forces).
  virtual Stages to_grid() const;
  //! From the transferred grid momentum to the grid velocity before the boundary conditions.
  virtual Stages grid_update() const = 0;
  //! From the final grid velocity to the new particle state: g2p (with the deformation update
  //! where the solver tracks F), then what follows it.
  virtual Stages particle_update() const = 0;
};

//! "explicit": symplectic Euler on the elastoplastic materials (explicit_solver.h).
//! "implicit": backward Euler on the same materials, Newton-CG (implicit_solver.h).
//! "grains": stress-free particles (discrete grains; gravity, and in a coupled scene buoyancy and
//! drag, move them).
std::vector<std::string> solid_solver_names();

//! The solver called `name` (one of solid_solver_names()) over `materials`. With
//! `stress_free_particles` some particles carry the index stress_free_material and add no stress
//! (a sediment that switches between continuum and discrete grains). The implicit solver
//! enforces `colliders` inside its solve, with `implicit` as its solve settings. InputError for
//! another name or for "explicit" or "implicit" without materials.
template <int dim>
std::shared_ptr<const SolidSolver<dim>> make_solid_solver(const std::string& name, std::vector<Material<dim>> materials,
                                                          bool stress_free_particles = false,
                                                          geometry::ColliderSet<dim> colliders = {},
                                                          const stages::ImplicitSettings& implicit = {});

//! The optional map `implicit` of `parent` (the scene, or a coupled scene's sediment): the
//! Newton and CG settings of solver `solver`. InputError naming file, line, key and range for
//! a value out of range, or for the map under another solver.
stages::ImplicitSettings parse_implicit_settings(const Config& parent, const std::string& solver);

}  // namespace mpm::solid
