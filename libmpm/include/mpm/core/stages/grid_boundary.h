#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

namespace mpm::stages {

//! Velocity conditions of walls and colliders on grid nodes (sticky, slip, separating with
//! Coulomb friction), evaluated at the end of the step, t + dt.
template <int dim>
class GridBoundary final : public Stage<MpmState<dim>> {
public:
  explicit GridBoundary(geometry::ColliderSet<dim> colliders) : colliders_(std::move(colliders)) {}
  std::string name() const override { return "boundary"; }
  std::vector<std::string> reads() const override { return {"grid.velocity"}; }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(MpmState<dim>& s) override;
  const geometry::ColliderSet<dim>& colliders() const { return colliders_; }

private:
  geometry::ColliderSet<dim> colliders_;
};

}  // namespace mpm::stages
