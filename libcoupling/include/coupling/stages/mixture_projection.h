#pragma once
//! The pressure projection of the mixture, drag implicit in the correction (docs/coupling.md).
#include <coupling/coupled_state.h>
#include <fluid/stages/pressure_projection.h>
#include <mpm/core/stage.h>

#include <string>
#include <vector>

namespace coupling::stages {

//! The mixture projection with the drag implicit in the pressure correction. The pressure
//! impulse and the drag of the same step are solved together per node, in the LANS form per
//! unit volume with b = beta dt [kg/m^3] (beta the drag coefficient of the step,
//! CoupledState::drag, which the exchange evaluated at the slip entering the step):
//!   [n_w rho_w + b, -b; -b, n_s rho_s + b] (v' - v*) = dt [n_w; n_s] D^T p,
//! so v_w' = v_w* + c_w D^T p and v_s' = v_s* + c_s D^T p with (c_w, c_s) = dt M^-1 (n_w, n_s).
//! The constraint D (n_w v_w' + n_s v_s') = 0 then reads D B D^T p = -D (n_w v_w* + n_s v_s*)
//! with the mixture mobility B = n_w c_w + n_s c_s: dt (n_w / rho_w + n_s / rho_s) without drag,
//! dt / (n_w rho_w + n_s rho_s) for infinite drag (the mixture moves as one). libfluid's
//! PressureProjection solves it through MixtureNodes (n_w, n_s v_s*, and the solid mobility
//! chosen so that its beta_i = dt (n_w / rho_w + mobility) equals B); it corrects
//! v_w += dt / rho_w D^T p, and this stage adds (c_w - dt / rho_w) D^T p to the fluid and
//! c_s D^T p to the sediment (D^T p = impulse / beta_i of CellOperator::subtract_gradient).
//! Without this the explicit pressure impulse would give stiff grains a slip of order
//! g dt (1 - rho_mix / rho_s) every step, far above their terminal velocity.
//! The mixture momentum sum_i V (n_w rho_w v_w + n_s rho_s v_s) changes by
//! dt V sum_i (D^T p)_i = 0 ((n_w rho_w, n_s rho_s) M^-1 = (1, 1)): round-off without walls.
//! Per unit volume the sediment feels -n_s grad p (buoyancy) and the drag it implies.
template <int dim>
class MixtureProjection final : public mpm::Stage<CoupledState<dim>> {
public:
  MixtureProjection(double fluid_density, double sediment_density, mpm::geometry::ColliderSet<dim> colliders,
                    fluid::stages::PressureSettings settings);
  std::string name() const override { return "mixture_pressure"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "drag", "fluid.grid.velocity", "sediment.grid.velocity", "fluid.particle.x"};
  }
  std::vector<std::string> writes() const override {
    return {"fluid.grid.velocity", "sediment.grid.velocity", "fluid.cell.pressure"};
  }
  void run(CoupledState<dim>& s) override;
  mpm::CarriedData carried() const override { return projection_.carried(); }
  void restore(const mpm::CarriedData& data) override { projection_.restore(data); }
  void synchronize(CoupledState<dim>& /*state*/) override { projection_.forget(); }
  std::vector<mpm::Diagnostic> diagnostics() const override { return projection_.diagnostics(); }

  const fluid::stages::PressureProjection<dim>& projection() const { return projection_; }

private:
  double rho_w_, rho_s_;
  fluid::stages::PressureProjection<dim> projection_;
  fluid::stages::MixtureNodes<dim> mixture_;
  std::vector<mpm::Index> sediment_node_;  // per fluid storage node: sediment storage or -1
  std::vector<double> c_w_, c_s_;          // per fluid storage node [m^3 s/kg]
  std::vector<mpm::Vec<dim>> impulse_;
};

}  // namespace coupling::stages
