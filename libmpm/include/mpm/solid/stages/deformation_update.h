#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! Updates the elastic deformation gradient with the grid velocity gradient, of every particle
//! (stress_free_material ones too: their owner resets F, so the loop stays branch-free).
template <int dim>
class DeformationUpdate final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "deformation"; }
  std::vector<std::string> reads() const override { return {"particle.order", "grid.velocity", "particle.F"}; }
  std::vector<std::string> writes() const override { return {"particle.F"}; }
  void run(MpmState<dim>& s) override;

private:
  std::vector<Mat<dim>> grad_v_;
};

}  // namespace mpm::stages
