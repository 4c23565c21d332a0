#pragma once
//! The volume fractions n_s, n_w of the shared nodes (LANS: the fractions weight
//! the momentum of each phase and the mixture constraint).
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>

#include <string>
#include <vector>

namespace coupling::stages {

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

}  // namespace coupling::stages
