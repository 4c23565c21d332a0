#pragma once
//! A coupled sediment-fluid scene and its pipeline (docs/coupling.md, "The coupled step";
//! docs/coupling.md). Either phase may be absent: a dry scene builds no fluid grid and no
//! pressure solver, a clear-fluid scene no sediment stages.
//!
//! The coupled step, one Stage<CoupledState> each (OnPhase runs a phase's own stage):
//!   time_step -> sort (both) -> p2g (fluid; the sediment solver's to_grid: explicit
//!   p2g_stress, grains p2g) -> volume_fraction -> the fluid solver's grid update (projection:
//!   grid_update (gravity) -> viscosity, mu > 0) -> the sediment solver's grid update
//!   (grid_update) -> exchange -> boundary (both) -> mixture_pressure (a clear fluid: the fluid
//!   solver's projection) -> boundary (sediment) -> the particle updates of both solvers (fluid:
//!   its particle update, then g2p; sediment: g2p, explicit with the deformation update and,
//!   when plastic, the return map: g2p_plasticity) -> reclassify (a continuum sediment with
//!   `switching`: stages/reclassify_sediment.h). With `bed_load` (coupling/bed_load.h):
//!   bed_surface before the exchange, bed_shear after it, bed_load after the sediment's g2p.
#include <coupling/bed_load.h>
#include <coupling/coupled_state.h>
#include <coupling/drag/drag_law.h>
#include <coupling/stages/reclassify_sediment.h>
#include <fluid/scene/fluid_scene.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/stages/particle_source.h>
#include <mpm/geometry/collider.h>
#include <mpm/geometry/flow_boundary_config.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_solver.h>

#include <memory>

#include <optional>
#include <string>
#include <vector>

namespace coupling {

template <int dim>
struct SedimentPhase {
  double density = 2650.0;  //!< grain material density rho_s [kg/m^3]
  //! The solid solver of the sediment (mpm/solid/solid_solver.h): "explicit" or "implicit" for a
  //! continuum of `materials`, "grains" for discrete grains that feel only gravity, buoyancy and
  //! drag (a dilute suspension; no materials).
  std::string solver = "grains";
  mpm::stages::ImplicitSettings implicit;  //!< the Newton and CG settings of "implicit"
  //! Drucker-Prager (or any libmpm) continuum of the sediment; empty with "grains".
  std::vector<mpm::Material<dim>> materials;
  double min_fluid_fraction = default_min_fluid_fraction;  //!< n_min of volume_fraction.h
  //! Continuum <-> discrete switching (needs materials); nullopt: every particle keeps its
  //! state and the pipeline has no reclassify stage.
  std::optional<SedimentSwitching> switching;
  //! The bed is held rigid while the time is below this [s] (stages/hold_sediment.h); 0: never.
  double hold_until = 0.0;
  //! The sediment's own contact with each collider of the scene, in order (scene key
  //! `colliders[i].sediment`): grains slide along and leave an obstacle whatever its contact
  //! with the water. nullopt, or past the end: the collider's contact.
  std::vector<std::optional<mpm::geometry::Contact>> contacts;
};

template <int dim>
struct CoupledScene {
  mpm::SceneSettings<dim> settings;
  mpm::geometry::ColliderSet<dim> colliders;
  //! The obstacles as the sediment meets them: `colliders` with SedimentPhase::contacts (equal
  //! to `colliders` without a sediment). Kept next to `colliders`: make_coupled_scene
  //! initialises the members in this order.
  mpm::geometry::ColliderSet<dim> sediment_colliders;
  std::optional<fluid::FluidMaterial> fluid;  //!< nullopt: dry scene
  fluid::stages::PressureSettings pressure;
  std::optional<SedimentPhase<dim>> sediment;  //!< nullopt: clear fluid
  std::optional<drag::DragLaw> drag;           //!< set iff both phases are
  //! The sediment's solid solver, built from SedimentPhase::solver (null without a sediment).
  std::shared_ptr<const mpm::solid::SolidSolver<dim>> solid_solver;
  //! The liquid's fluid solver (fluid/solver/fluid_solver.h; null without a fluid). With a
  //! sediment the mixture projection stands in for an incompressible solver's projection; a
  //! weakly compressible liquid carries the pore pressure itself (stages/pore_pressure.h).
  std::shared_ptr<const fluid::FluidSolver<dim>> fluid_solver;
  CoupledState<dim> state;
  //! Inflow and outflow (flow_boundary_config.h), already applied to `colliders`: the inflow
  //! emits fluid (fraction 1), the outflow removes particles of both phases.
  mpm::geometry::FlowBoundaries<dim> flow;
  //! The emitters of each phase (the inflow's among the fluid's), one source stage each.
  std::vector<typename mpm::stages::ParticleSource<dim>::Settings> fluid_sources, sediment_sources;
  //! The bed-load closure at the bed surface (coupling/bed_load.h; scene key `bed_load`);
  //! nullopt: the drag acts at the bed surface as everywhere, and the pipeline has no bed stages.
  std::optional<BedLoadLaw> bed_load;
};

//! A scene without particles; a grid is allocated for each phase present. InputError when
//! both phases are present without a drag law, or neither is, or the sediment's solver does
//! not match its materials (explicit needs them, grains has none), or it switches without a
//! continuum material.
template <int dim>
CoupledScene<dim> make_coupled_scene(mpm::SceneSettings<dim> settings, mpm::geometry::ColliderSet<dim> colliders,
                                     std::optional<fluid::FluidMaterial> fluid,
                                     fluid::stages::PressureSettings pressure,
                                     std::optional<SedimentPhase<dim>> sediment, std::optional<drag::DragLaw> drag,
                                     const fluid::FluidSolverSettings& fluid_solver = {});

//! Fluid particles of volume `volume` [m^dim] each, in a region of fluid fraction n_w (the
//! particle mass is n_w rho_w V_p, Gao et al. 2018); InputError naming `where` when one lies
//! outside the domain.
template <int dim>
void add_fluid_particles(CoupledScene<dim>& scene, const std::vector<mpm::Vec<dim>>& positions, double volume,
                         double fluid_fraction, const mpm::Vec<dim>& velocity, const std::string& where);

//! Sediment particles holding grain volume `grain_volume` [m^dim] each (mass rho_s V_p), of
//! the scene's first sediment material when it has materials, discrete grains (material
//! index discrete_grain) otherwise.
template <int dim>
void add_sediment_particles(CoupledScene<dim>& scene, const std::vector<mpm::Vec<dim>>& positions, double grain_volume,
                            const mpm::Vec<dim>& velocity, const std::string& where);

//! The axis gravity points down along (y in the shipped scenes); InputError unless gravity lies
//! along one axis and points towards its negative end.
template <int dim>
int vertical_axis(const mpm::SceneSettings<dim>& settings);
//! The coupled pipeline of the header comment for the phases `scene` holds.
template <int dim>
mpm::Pipeline<CoupledState<dim>> make_coupled_pipeline(const CoupledScene<dim>& scene);

}  // namespace coupling
