#pragma once
//! Holds a sediment bed rigid while the flow over it develops (scene key `sediment.hold_until`):
//! morphodynamic scour runs start from the current over a fixed bed and release the bed once
//! the flow is set up (e.g. Liang & Cheng 2005 for pipelines), since a current started at full
//! speed against an obstacle on the bed strikes it with an impulse no flume's slowly started
//! pump gives. Until then the sediment's grid velocities are zero before its g2p, so its
//! particles keep x, F and their state (APIC and PIC; a FLIP particle keeps a share of its own
//! velocity), and the bed-load drift of the step is dropped; the
//! water still feels the held grains through the drag, as flow through a fixed porous bed.
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>

#include <string>
#include <vector>

namespace coupling::stages {

template <int dim>
class HoldSediment final : public mpm::Stage<CoupledState<dim>> {
public:
  explicit HoldSediment(double until) : until_(until) {}
  std::string name() const override { return "hold_sediment"; }
  std::vector<std::string> reads() const override { return {"sediment.grid.velocity"}; }
  std::vector<std::string> writes() const override { return {"sediment.grid.velocity", "bed"}; }
  void run(CoupledState<dim>& s) override {
    if (!(s.time < until_)) return;
    for (mpm::Vec<dim>& v : s.sediment.grid.velocity) v.setZero();
    for (mpm::Vec<dim>& v : s.sediment.grid.velocity_old) v.setZero();  // FLIP's
    s.bed.particle_drift.clear();
  }

private:
  double until_;  //!< [s]
};

}  // namespace coupling::stages
