#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! Orders particles by grid block and allocates the blocks their stencils touch.
template <int dim>
class SortParticles final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "sort"; }
  std::vector<std::string> reads() const override { return {"particle.x"}; }
  std::vector<std::string> writes() const override { return {"particle.order", "grid.blocks"}; }
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
