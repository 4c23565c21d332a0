#pragma once
#include <mpm/adaptive/cell_tree.h>
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! Adaptive grids only: rebuilds the tree every step from the static refinement and the
//! particles: a cell is refined while it holds a particle of a finer type (Gao et al. 2017,
//! sec. 7.1, "the grid and particle adaptations are completely determined by the particle
//! types"), so the fine cells follow the fine particles. The tree is a function of the
//! particles at the start of the step, so a restart rebuilds it exactly.
template <int dim>
class RefineGrid final : public Stage<MpmState<dim>> {
public:
  RefineGrid(adaptive::CellTree<dim> static_tree, bool padding)
      : static_tree_(std::move(static_tree)), padding_(padding) {}
  std::string name() const override { return "refine"; }
  std::vector<std::string> reads() const override { return {"particle.x", "particle.level"}; }
  std::vector<std::string> writes() const override { return {"grid.tree"}; }
  void run(MpmState<dim>& s) override;

private:
  adaptive::CellTree<dim> static_tree_;
  bool padding_;  //!< adaptive::refine_around_particles' padding
};

}  // namespace mpm::stages
