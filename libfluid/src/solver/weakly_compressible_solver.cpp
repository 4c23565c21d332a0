#include <fluid/solver/weakly_compressible_solver.h>

#include <mpm/core/stages/grid_velocity_update.h>

namespace fluid {

template <int dim>
typename WeaklyCompressibleSolver<dim>::Stages WeaklyCompressibleSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::EquationOfStateForces<dim>>(eos_));
  s.push_back(std::make_unique<mpm::stages::GridVelocityUpdate<dim>>(true));
  append_viscosity<dim>(s, fluid_, colliders_);
  return s;
}

template <int dim>
typename WeaklyCompressibleSolver<dim>::Stages WeaklyCompressibleSolver<dim>::particle_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::VolumeRatioUpdate<dim>>());
  return s;
}

template class WeaklyCompressibleSolver<2>;
template class WeaklyCompressibleSolver<3>;

}  // namespace fluid
