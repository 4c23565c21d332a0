#include <fluid/solver/projection_solver.h>

#include <fluid/stages/pressure_projection.h>
#include <fluid/stages/surface_velocity_extension.h>

#include <mpm/core/stages/grid_velocity_update.h>

namespace fluid {

template <int dim>
typename ProjectionSolver<dim>::Stages ProjectionSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<mpm::stages::GridVelocityUpdate<dim>>(false));
  append_viscosity<dim>(s, fluid_, colliders_);
  return s;
}

template <int dim>
typename ProjectionSolver<dim>::Stages ProjectionSolver<dim>::projection() const {
  Stages s;
  s.push_back(std::make_unique<stages::PressureProjection<dim>>(fluid_.density, colliders_, pressure_));
  if (pressure_.surface_extension) s.push_back(std::make_unique<stages::SurfaceVelocityExtension<dim>>(colliders_));
  return s;
}

template class ProjectionSolver<2>;
template class ProjectionSolver<3>;

}  // namespace fluid
