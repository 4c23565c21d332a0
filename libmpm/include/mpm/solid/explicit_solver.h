#pragma once
//! The explicit symplectic-Euler elastoplastic step (docs/architecture.md, "The explicit solid
//! step"): to_grid() = p2g with the stress forces in the same scatter (p2g_stress);
//! grid_update() = grid_update (forces and gravity); particle_update() = g2p with the
//! deformation update and, when a material is plastic, the return map of each bucket right
//! after its gather (g2p_plasticity). Stable for dt < dx / c, c the fastest elastic wave of the
//! materials.
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_solver.h>

namespace mpm::solid {

template <int dim>
class ExplicitSolver final : public SolidSolver<dim> {
public:
  using typename SolidSolver<dim>::Stages;
  ExplicitSolver(std::vector<Material<dim>> materials, bool stress_free_particles);
  std::string name() const override { return "explicit"; }
  //! F and plastic; the stress cache too when a material is plastic.
  void add_channels(Particles<dim>& particles) const override;
  double wave_speed() const override;
  Stages to_grid() const override;
  Stages grid_update() const override;
  Stages particle_update() const override;

private:
  std::vector<Material<dim>> materials_;
  bool stress_free_particles_;
};

//! Particles that carry no stress: the grid update adds gravity only and the particles keep no
//! deformation state.
template <int dim>
class GrainSolver final : public SolidSolver<dim> {
public:
  using typename SolidSolver<dim>::Stages;
  std::string name() const override { return "grains"; }
  void add_channels(Particles<dim>& /*particles*/) const override {}
  double wave_speed() const override { return 0.0; }
  Stages grid_update() const override;
  Stages particle_update() const override;  //!< g2p alone
};

}  // namespace mpm::solid
