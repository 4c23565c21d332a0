#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! G2P and advection: v_p, C_p from the grid; x_p += dt v_p^PIC.
template <int dim>
class GridToParticles final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "g2p"; }
  std::vector<std::string> reads() const override { return {"grid.velocity", "particle.order"}; }
  std::vector<std::string> writes() const override { return {"particle.v", "particle.C", "particle.x"}; }
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
