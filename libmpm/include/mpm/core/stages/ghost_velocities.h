#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! Adaptive grids only: fills the ghost nodes' velocities from their real nodes (Gao et al.
//! 2017, sec. 6.1) after the grid update and the boundary conditions, for the stages that
//! read grid velocities at the particles (deformation, G2P).
template <int dim>
class GhostVelocities final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "ghost_velocities"; }
  std::vector<std::string> reads() const override { return {"grid.velocity"}; }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
