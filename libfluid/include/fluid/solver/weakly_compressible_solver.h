#pragma once
//! A weakly compressible liquid: each particle carries its volume ratio J and its pressure follows
//! from J by the Tait equation of state (fluid/stages/equation_of_state.h), so a step solves no
//! linear system. grid_update() = pressure_forces -> grid_update (forces and gravity) ->
//! viscosity (implicit, only when mu > 0); projection() = nothing; particle_update() =
//! volume_ratio. The step resolves the speed of sound c (dt <= wave_cfl dx / c), and the liquid
//! compresses by about (|v| / c)^2: the density_deviation column reports it. A clear fluid only:
//! a sediment needs the mixture projection of an incompressible solver.
#include <fluid/solver/fluid_solver.h>
#include <fluid/stages/equation_of_state.h>

namespace fluid {

template <int dim>
class WeaklyCompressibleSolver final : public FluidSolver<dim> {
public:
  using typename FluidSolver<dim>::Stages;
  WeaklyCompressibleSolver(FluidMaterial fluid, TaitEquationOfState eos, mpm::geometry::ColliderSet<dim> colliders,
                           double wave_speed)
      : fluid_(fluid), eos_(eos), colliders_(std::move(colliders)), wave_speed_(wave_speed) {}
  std::string name() const override { return "weakly_compressible"; }
  bool incompressible() const override { return false; }
  void add_channels(mpm::Particles<dim>& particles) const override {
    particles.template add_channel<double>(kVolumeRatio, 1.0, {.output = true, .checkpoint = true});
  }
  double wave_speed() const override { return wave_speed_; }
  Stages grid_update() const override;
  Stages projection() const override { return {}; }
  Stages particle_update() const override;

private:
  FluidMaterial fluid_;
  TaitEquationOfState eos_;
  mpm::geometry::ColliderSet<dim> colliders_;
  double wave_speed_;
};

}  // namespace fluid
