#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/solid/material.h>

namespace mpm::stages {

//! Internal elastic forces on grid nodes from the particles' Kirchhoff stress.
template <int dim>
class StressForces final : public Stage<MpmState<dim>> {
public:
  explicit StressForces(std::vector<Material<dim>> materials) : materials_(std::move(materials)) {}
  std::string name() const override { return "stress_forces"; }
  std::vector<std::string> reads() const override {
    return {"particle.order", "grid.blocks", "particle.x", "particle.volume0", "particle.material", "particle.F"};
  }
  std::vector<std::string> writes() const override { return {"grid.force"}; }
  void run(MpmState<dim>& s) override;

private:
  std::vector<Material<dim>> materials_;
  std::vector<Mat<dim>> weighted_stress_;  // V_p^0 tau_p per particle [N m]
};

}  // namespace mpm::stages
