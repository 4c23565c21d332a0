#pragma once
//! A weakly compressible liquid: each particle carries its volume ratio J and its pressure follows
//! from J by the Tait equation of state (fluid/stages/equation_of_state.h), so a step solves no
//! linear system. grid_update() = pressure_forces -> wall_pressure (the closed domain walls'
//! push, from images of the particles next to them) -> grid_update (forces and gravity) ->
//! viscosity (implicit, only when mu > 0); projection() = nothing; particle_update() =
//! volume_ratio. The step resolves the speed of sound c (dt <= wave_cfl dx / c), and the liquid
//! compresses by about (|v| / c)^2: the density_deviation column reports it. A clear fluid only:
//! a sediment needs the mixture projection of an incompressible solver.
//!
//! Seeded at J = 1, a liquid under gravity carries no pressure, falls and rings with sound
//! waves that nothing damps in an inviscid liquid (a tank at rest kept 0.76 rho g h of pressure
//! error after 1 s). start_at_rest therefore compresses it to hydrostatic equilibrium first, as
//! weakly compressible SPH initialises its density (Monaghan 1994, sec. 4): with gravity along
//! a grid axis, a particle at depth d below the free surface of its dx-wide column of liquid
//! gets p = rho_0 |g| d, J = (1 + p / B)^(-1/gamma). A scene whose gravity is zero or not along
//! an axis starts at J = 1, and so does one with `fluid.initial_pressure: zero` (a liquid in free
//! fall carries no pressure).
#include <fluid/solver/fluid_solver.h>
#include <fluid/stages/equation_of_state.h>

namespace fluid {

template <int dim>
class WeaklyCompressibleSolver final : public FluidSolver<dim> {
public:
  using typename FluidSolver<dim>::Stages;
  WeaklyCompressibleSolver(FluidMaterial fluid, TaitEquationOfState eos, mpm::geometry::ColliderSet<dim> colliders,
                           double wave_speed, bool hydrostatic_start = true)
      : fluid_(fluid),
        eos_(eos),
        colliders_(std::move(colliders)),
        wave_speed_(wave_speed),
        hydrostatic_start_(hydrostatic_start) {}
  std::string name() const override { return "weakly_compressible"; }
  bool incompressible() const override { return false; }
  void add_channels(mpm::Particles<dim>& particles) const override {
    particles.template add_channel<double>(kVolumeRatio, 1.0, {.output = true, .checkpoint = true});
  }
  void start_at_rest(mpm::Particles<dim>& particles, const mpm::SceneSettings<dim>& settings) const override;
  double wave_speed() const override { return wave_speed_; }
  const TaitEquationOfState& equation_of_state() const { return eos_; }
  Stages grid_update() const override;
  Stages projection() const override { return {}; }
  Stages particle_update() const override;

private:
  FluidMaterial fluid_;
  TaitEquationOfState eos_;
  mpm::geometry::ColliderSet<dim> colliders_;
  double wave_speed_;
  bool hydrostatic_start_;  //!< fluid.initial_pressure: hydrostatic (else start_at_rest keeps J = 1)
};

}  // namespace fluid
