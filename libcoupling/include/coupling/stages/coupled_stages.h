#pragma once
//! The stages of the coupled step that act on both phases (DESIGN.md, "the coupled step";
//! docs/coupling.md, "The coupled step"). The single-phase stages run through OnPhase.
#include <coupling/coupled_state.h>
#include <coupling/momentum_exchange.h>
#include <fluid/stages/pressure_projection.h>
#include <mpm/core/stage.h>
#include <mpm/core/stages/time_step_control.h>

#include <string>
#include <vector>

namespace coupling::stages {

//! dt = min over the phases present of their stable step (particle CFL, wave speed: the
//! free-fall limit of the fluid, the elastic wave of a continuum sediment), clipped to the
//! frame end; copies time, dt and step into both phase states.
template <int dim>
class CoupledTimeStep final : public mpm::Stage<CoupledState<dim>> {
 public:
  using Settings = typename mpm::stages::TimeStepControl<dim>::Settings;
  CoupledTimeStep(Settings fluid, Settings sediment) : fluid_(fluid), sediment_(sediment) {}
  std::string name() const override { return "time_step"; }
  std::vector<std::string> reads() const override { return {}; }
  std::vector<std::string> writes() const override { return {"dt"}; }
  void run(CoupledState<dim>& s) override;

 private:
  mpm::stages::TimeStepControl<dim> fluid_, sediment_;
};

//! n_s and n_w per sediment node. Where both phases hold mass, the mixture volume of the node
//! is the grain volume m_s / rho_s plus the liquid volume m_w / rho_w (fluid particles carry
//! n_w rho_w V_p), so phi_i = (m_s / rho_s) / (m_s / rho_s + m_w / rho_w): in the interior it
//! is sum_p w_ip V_p / V_i (volume_fraction.h), and next to walls and free surfaces, where the
//! kernel covers a node only in part, both volumes lose the same share and phi stays exact
//! (phi_i = m_s / (rho_s V_i) there underestimates n_s, makes those nodes look light and drives
//! a spurious convection along the walls). Dry nodes: phi_i = m_s / (rho_s dx^dim). Then
//! clamped with the floor n_min.
template <int dim>
class VolumeFractionStage final : public mpm::Stage<CoupledState<dim>> {
 public:
  VolumeFractionStage(double fluid_density, double sediment_density, double min_fluid_fraction)
      : rho_w_(fluid_density), rho_s_(sediment_density), min_fluid_(min_fluid_fraction) {}
  std::string name() const override { return "volume_fraction"; }
  std::vector<std::string> reads() const override { return {"sediment.grid.mass", "fluid.grid.mass"}; }
  std::vector<std::string> writes() const override { return {"fractions"}; }
  void run(CoupledState<dim>& s) override;

 private:
  double rho_w_, rho_s_, min_fluid_;
  std::vector<double> phi_;
};

//! The implicit drag exchange of momentum_exchange.h on the shared nodes.
template <int dim>
class ExchangeStage final : public mpm::Stage<CoupledState<dim>> {
 public:
  explicit ExchangeStage(drag::DragLaw law) : exchange_(law) {}
  std::string name() const override { return "exchange"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "fluid.grid.velocity", "sediment.grid.velocity"};
  }
  std::vector<std::string> writes() const override {
    return {"fluid.grid.velocity", "sediment.grid.velocity"};
  }
  void run(CoupledState<dim>& s) override {
    exchange_.apply(s.fluid.grid, s.sediment.grid, s.fractions.fluid, s.dt);
  }

 private:
  MomentumExchange<dim> exchange_;
};

//! The mixture projection with the drag implicit in the pressure correction. The pressure
//! impulse and the drag of the same step are solved together per node, in the LANS form per
//! unit volume with b = beta dt [kg/m^3] (beta the drag coefficient at the slip after the
//! exchange):
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
  MixtureProjection(double fluid_density, double sediment_density, drag::DragLaw law,
                    mpm::geometry::ColliderSet<dim> colliders, fluid::stages::PressureSettings settings);
  std::string name() const override { return "mixture_pressure"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "fluid.grid.velocity", "sediment.grid.velocity", "fluid.particle.x"};
  }
  std::vector<std::string> writes() const override {
    return {"fluid.grid.velocity", "sediment.grid.velocity", "fluid.cell.pressure"};
  }
  void run(CoupledState<dim>& s) override;
  mpm::CarriedData carried() const override { return projection_.carried(); }
  void restore(const mpm::CarriedData& data) override { projection_.restore(data); }

  const fluid::stages::PressureProjection<dim>& projection() const { return projection_; }

 private:
  double rho_w_, rho_s_;
  drag::DragLaw law_;
  fluid::stages::PressureProjection<dim> projection_;
  fluid::stages::MixtureNodes<dim> mixture_;
  std::vector<mpm::Index> sediment_node_;  // per fluid storage node: sediment storage or -1
  std::vector<double> c_w_, c_s_;          // per fluid storage node [m^3 s/kg]
  std::vector<mpm::Vec<dim>> impulse_;
};

}  // namespace coupling::stages
