#pragma once
//! The implicit (backward Euler) elastoplastic step: grid_update() = implicit_update (Newton
//! on the incremental potential, stages/implicit_update.h); particle_update() = g2p with the
//! deformation update -> plasticity, as in the explicit step. Stable at any step: the time step follows the particle
//! CFL condition alone, not the elastic wave speed.
#include <mpm/geometry/collider.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_solver.h>
#include <mpm/solid/stages/implicit_update.h>

namespace mpm::solid {

template <int dim>
class ImplicitSolver final : public SolidSolver<dim> {
public:
  using typename SolidSolver<dim>::Stages;
  //! Particles of no listed material (stress-free grains) add no stress.
  ImplicitSolver(std::vector<Material<dim>> materials, geometry::ColliderSet<dim> colliders,
                 stages::ImplicitSettings settings);
  std::string name() const override { return "implicit"; }
  void add_channels(Particles<dim>& particles) const override { add_solid_channels(particles); }
  double wave_speed() const override { return 0.0; }
  Stages grid_update() const override;
  Stages particle_update() const override;

private:
  std::vector<Material<dim>> materials_;
  geometry::ColliderSet<dim> colliders_;
  stages::ImplicitSettings settings_;
};

}  // namespace mpm::solid
