#pragma once
//! The incompressible free-surface LANS step (Gao et al. 2018; docs/architecture.md, "The fluid
//! step"): grid_update() = grid_update (gravity) -> viscosity (implicit, only when mu > 0);
//! projection() = pressure (the node/cell projection, fluid/stages/pressure_projection.h) ->
//! surface_extension (fluid/stages/surface_velocity_extension.h, unless pressure.surface_extension
//! is off);
//! particle_update() = nothing. Its time step is limited by the free fall of the surface, not
//! by a wave: the pressure is implicit.
#include <fluid/solver/fluid_solver.h>

namespace fluid {

template <int dim>
class ProjectionSolver final : public FluidSolver<dim> {
public:
  using typename FluidSolver<dim>::Stages;
  ProjectionSolver(FluidMaterial fluid, stages::PressureSettings pressure, mpm::geometry::ColliderSet<dim> colliders,
                   double wave_speed)
      : fluid_(fluid), pressure_(std::move(pressure)), colliders_(std::move(colliders)), wave_speed_(wave_speed) {}
  std::string name() const override { return "projection"; }
  bool incompressible() const override { return true; }
  void add_channels(mpm::Particles<dim>& /*particles*/) const override {}
  double wave_speed() const override { return wave_speed_; }
  Stages grid_update() const override;
  Stages projection() const override;
  Stages particle_update() const override { return {}; }

private:
  FluidMaterial fluid_;
  stages::PressureSettings pressure_;
  mpm::geometry::ColliderSet<dim> colliders_;
  double wave_speed_;
};

}  // namespace fluid
