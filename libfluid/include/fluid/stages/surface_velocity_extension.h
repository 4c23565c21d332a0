#pragma once
//! The projected velocity extended to the nodes just outside the liquid (free surface).
//!
//! The projection acts on the corners of the fluid cells (cells holding a particle). The
//! kernel reaches further: a particle near the top of its cell gives mass to the node row above
//! the cell's corners (quadratic B-spline, 1.5 dx), and no fluid cell has that node as a
//! corner, so no pressure reaches it and it keeps the explicit update v* (free fall). G2P then
//! hands every surface particle a share of g (1/32 of it for the top particles of water at
//! rest, 4 particles per cell): the spurious surface currents of a tank at rest.
//!
//! The stage gives each such "loose" node (mass > 0, no corner of a fluid cell, velocity not
//! held by a wall or collider; a node slipping along one gets the tangential part) the mean
//! velocity of its neighbours (3^dim box) that the
//! projection reached, layer by layer outwards (each layer from the previous ones only, so the
//! result does not depend on node order), as FLIP liquids extrapolate the grid velocity into
//! the air (Zhu & Bridson 2005). Water at rest
//! then stays at rest to the tolerance of the pressure solve. It changes the momentum by
//! sum_loose m_i (v_i - v_i*): nothing in free fall (every node has v*), the gravity impulse of
//! the loose mass for water at rest, and in general the pressure impulse of the neighbours the
//! loose nodes now share (a squeezed falling blob: 0.45 % of sum m |v| against 0.30 % without,
//! test_coupled_step); the projection's own conservation is untouched (it runs before). Runs
//! after the projection, before periodic_fill.
#include <mpm/core/stage.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fluid::stages {

template <int dim>
class SurfaceVelocityExtension final : public mpm::Stage<mpm::MpmState<dim>> {
public:
  explicit SurfaceVelocityExtension(mpm::geometry::ColliderSet<dim> colliders) : colliders_(std::move(colliders)) {}

  std::string name() const override { return "surface_extension"; }
  std::vector<std::string> reads() const override { return {"grid.mass", "grid.velocity", "particle.x"}; }
  std::vector<std::string> writes() const override { return {"grid.velocity"}; }
  void run(mpm::MpmState<dim>& s) override;
  //! surface_nodes_extended: the loose nodes the last step gave a velocity.
  std::vector<mpm::Diagnostic> diagnostics() const override { return {{"surface_nodes_extended", double(extended_)}}; }

private:
  mpm::geometry::ColliderSet<dim> colliders_;
  std::vector<std::uint8_t> state_;  // per storage node: 0 loose, 1 reached (or held), 2 no mass
  std::vector<mpm::Index> layer_;
  std::vector<mpm::Vec<dim>> extended_velocity_;
  std::vector<std::int32_t> slip_index_;       // per storage node: its slip_projector_, or -1
  std::vector<mpm::Mat<dim>> slip_projector_;  // the free directions of loose slipping nodes
  std::int64_t extended_ = 0;
};

}  // namespace fluid::stages
