#pragma once
//! The bed-load closure's stages (coupling/bed_load.h): bed_surface before the exchange (finds
//! the layer, the wall stress and the drift, keeps the velocities the exchange starts from),
//! bed_shear after it (limits the layer's tangential drag to the wall stress and gathers the
//! drift to the particles), bed_load after the sediment's g2p (moves the grains by the drift).
#include <coupling/bed_load.h>
#include <coupling/coupled_state.h>
#include <mpm/core/stage.h>
#include <mpm/geometry/collider.h>

#include <string>
#include <utility>
#include <vector>

namespace coupling::stages {

template <int dim>
class BedSurface final : public mpm::Stage<CoupledState<dim>> {
public:
  BedSurface(BedLoadLaw law, int up, mpm::geometry::ColliderSet<dim> obstacles)
      : law_(law), up_(up), obstacles_(std::move(obstacles)) {}
  std::string name() const override { return "bed_surface"; }
  std::vector<std::string> reads() const override {
    return {"fractions", "fluid.grid.velocity", "sediment.grid.velocity"};
  }
  std::vector<std::string> writes() const override { return {"bed"}; }
  void run(CoupledState<dim>& s) override {
    find_bed_layer(law_, up_, s.fluid.grid, s.sediment.grid, s.fractions, obstacles_, s.time + s.dt, s.bed);
    shields_ = s.bed.largest_shields;
  }
  //! The largest Shields number over the columns in the last step.
  std::vector<mpm::Diagnostic> diagnostics() const override { return {{"bed_shields", shields_}}; }

private:
  BedLoadLaw law_;
  int up_;
  mpm::geometry::ColliderSet<dim> obstacles_;
  double shields_ = 0.0;
};

template <int dim>
class BedShear final : public mpm::Stage<CoupledState<dim>> {
public:
  std::string name() const override { return "bed_shear"; }
  std::vector<std::string> reads() const override {
    return {"bed", "fluid.grid.velocity", "sediment.grid.velocity", "sediment.particle.x"};
  }
  std::vector<std::string> writes() const override { return {"fluid.grid.velocity", "sediment.grid.velocity", "bed"}; }
  void run(CoupledState<dim>& s) override;
  std::vector<mpm::Diagnostic> diagnostics() const override { return {{"bed_columns_limited", double(limited_)}}; }

private:
  std::size_t limited_ = 0;
  std::vector<double> node_drift_, particle_drift_;
};

//! Moves each grain by dt times its drift, unless that would put it where the obstacles
//! prescribe the velocity (ColliderSet::prescribes: inside or on a collider, in a closed wall's
//! layer): a grain rolling against a pipe, a weir or a flume's side wall stops there.
template <int dim>
class BedLoadDrift final : public mpm::Stage<CoupledState<dim>> {
public:
  explicit BedLoadDrift(mpm::geometry::ColliderSet<dim> colliders) : colliders_(std::move(colliders)) {}
  std::string name() const override { return "bed_load"; }
  std::vector<std::string> reads() const override { return {"bed", "sediment.particle.x"}; }
  std::vector<std::string> writes() const override { return {"sediment.particle.x"}; }
  void run(CoupledState<dim>& s) override;

private:
  mpm::geometry::ColliderSet<dim> colliders_;
};

}  // namespace coupling::stages
