#pragma once
//! A weakly compressible liquid in the pores of a sediment (docs/coupling.md, "A weakly
//! compressible liquid in a mixture"): the liquid's pressure follows from its own volume by the
//! equation of state (fluid/stages/equation_of_state.h) instead of a mixture projection, and
//! acts on each phase by its volume fraction.
//!
//! The liquid's own volume. With incompressible grains the two mass balances add up to the
//! storage equation of a saturated porous medium (the u-p form of two-phase MPM, e.g. Bandara &
//! Soga 2015): n_w D_w(ln V_own) = div(n_w v_w + n_s v_s) following the liquid, so the liquid
//! is compressed exactly where the mixture flux converges, the quantity the mixture projection
//! holds at zero. A liquid particle keeps J (volume_ratio, its mixture volume, det of the
//! liquid's deformation: the volume its forces are integrated over) and its own volume ratio
//! J_own = V_own / V^0 (fluid::kLiquidVolumeRatio, the one its pressure follows; it starts
//! equal to J, so a bed seeded at rest keeps the hydrostatic start of
//! WeaklyCompressibleSolver::start_at_rest). LiquidVolumeUpdate advances it from the final grid
//! velocities of the step:
//!   J_own <- J_own (1 + dt tr(grad u)_p / n_w,p),   u_i = n_w,i v_w,i + n_s,i v_s,i.
//!
//! The pressure forces f_i = sum_p V_p^0 J_p p_p grad w_ip of the liquid's particles are -grad p
//! integrated over the node's mixture volume; the LANS momentum balances give -n_w grad p to
//! the liquid and -n_s grad p to the grains (buoyancy), so PorePressureShare moves the impulse
//! dt n_s,i f_i of every node from the liquid to the sediment: the mixture's momentum is
//! unchanged and the drag exchange that follows (ExchangeStage) acts on the shared velocities.
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>

#include <string>
#include <vector>

namespace coupling::stages {

//! J_own as above from the grid velocities after the exchange and the boundary conditions, u
//! and n_w read at the particles with the G2P weights (n_s = 0 where the sediment has no node).
template <int dim>
class LiquidVolumeUpdate final : public mpm::Stage<CoupledState<dim>> {
public:
  std::string name() const override { return "liquid_volume"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "fluid.grid.velocity", "sediment.grid.velocity", "fluid.particle.order"};
  }
  std::vector<std::string> writes() const override { return {"fluid.particle.liquid_volume_ratio"}; }
  void run(CoupledState<dim>& s) override;

private:
  std::vector<double> node_fraction_, particle_fraction_;
  std::vector<mpm::Vec<dim>> flux_;
  std::vector<mpm::Mat<dim>> grad_flux_;
};

//! v_w -= dt n_s f_i / m_w, v_s += dt n_s f_i / m_s at every node the two grids share, f_i the
//! liquid's pressure forces (fluid grid.force), after both grid updates.
template <int dim>
class PorePressureShare final : public mpm::Stage<CoupledState<dim>> {
public:
  std::string name() const override { return "pore_pressure_share"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "fluid.grid.force", "fluid.grid.mass", "sediment.grid.mass"};
  }
  std::vector<std::string> writes() const override { return {"fluid.grid.velocity", "sediment.grid.velocity"}; }
  void run(CoupledState<dim>& s) override;
};

}  // namespace coupling::stages
