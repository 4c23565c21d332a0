#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/solid/material.h>

namespace mpm::stages {

//! Internal elastic forces on grid nodes from the particles' Kirchhoff stress. A scene whose
//! particles may carry an index outside the material list (stress_free_material: discrete
//! grains) says so with `stress_free_particles`; those particles then add no force. Without it
//! every particle must hold a listed material and the loop is that of a plain solid.
template <int dim>
class StressForces final : public Stage<MpmState<dim>> {
public:
  explicit StressForces(std::vector<Material<dim>> materials, bool stress_free_particles = false)
      : materials_(std::move(materials)), stress_free_particles_(stress_free_particles) {}
  std::string name() const override { return "stress_forces"; }
  std::vector<std::string> reads() const override {
    return {"particle.order",    "grid.blocks", "particle.x",      "particle.volume0",
            "particle.material", "particle.F",  "particle.plastic"};
  }
  std::vector<std::string> writes() const override { return {"grid.force"}; }
  void run(MpmState<dim>& s) override;

private:
  std::vector<Material<dim>> materials_;
  bool stress_free_particles_;
  std::vector<Mat<dim>> weighted_stress_;  // V_p^0 tau_p per particle [N m]
};

}  // namespace mpm::stages
