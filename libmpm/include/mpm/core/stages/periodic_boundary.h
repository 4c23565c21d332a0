#pragma once
//! Periodic axes of the sparse grid (sparse_grid.h): node j and node j + N are one node.
//! Ghost nodes (beyond [lo, hi) on a periodic axis) receive P2G contributions like any node;
//! PeriodicFold adds them onto their canonical images and copies the sums back, PeriodicFill
//! copies the canonical velocities into the ghosts before G2P, and PeriodicWrap moves the
//! particles that left [lo, hi) back by whole periods. The stages are added only to scenes
//! with a periodic axis, so other scenes pay nothing.
#include <mpm/core/stage.h>
#include <mpm/core/state.h>

namespace mpm::stages {

//! After P2G: m_i <- sum over the images j of i of m_j (same for momentum), on every image.
template <int dim>
class PeriodicFold final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "periodic_fold"; }
  std::vector<std::string> reads() const override { return {"grid.mass", "grid.momentum"}; }
  std::vector<std::string> writes() const override { return {"grid.mass", "grid.momentum"}; }
  void run(MpmState<dim>& s) override;
};

//! Before G2P: v_ghost <- v_image (and the FLIP velocity_old when the scheme keeps it), after
//! the grid stages that update only canonical nodes (viscosity, pressure).
template <int dim>
class PeriodicFill final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "periodic_fill"; }
  std::vector<std::string> reads() const override { return {"grid.velocity"}; }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(MpmState<dim>& s) override;
};

//! After advection: x_a <- lo_a + ((x_a - lo_a) mod L_a) on periodic axes (L_a = N_a dx).
template <int dim>
class PeriodicWrap final : public Stage<MpmState<dim>> {
public:
  std::string name() const override { return "periodic_wrap"; }
  std::vector<std::string> reads() const override { return {"particle.x"}; }
  std::vector<std::string> writes() const override { return {"particle.x"}; }
  void run(MpmState<dim>& s) override;
};

}  // namespace mpm::stages
