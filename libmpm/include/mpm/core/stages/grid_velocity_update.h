#pragma once
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! Explicit grid update: v_i = (m v)_i / m_i + dt (f_i / m_i + g), on every level of an
//! adaptive grid (its ghosts hold no mass).
template <int dim>
class GridVelocityUpdate final : public Stage<MpmState<dim>> {
public:
  //! `with_forces`: add grid.force (written by a force stage such as the solid's stress).
  explicit GridVelocityUpdate(bool with_forces) : with_forces_(with_forces) {}
  std::string name() const override { return "grid_update"; }
  std::vector<std::string> reads() const override {
    if (with_forces_) return {"grid.mass", "grid.momentum", "grid.force"};
    return {"grid.mass", "grid.momentum"};
  }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(MpmState<dim>& s) override;

private:
  void update(SparseGrid<dim>& grid, const MpmState<dim>& s) const;
  bool with_forces_;
};

}  // namespace mpm::stages
