#pragma once
//! The state a single-phase MPM pipeline advances: one particle set on one sparse grid.
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/particles.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/sparse_grid.h>
#include <mpm/core/transfer.h>

#include <string>
#include <vector>

namespace mpm {

template <int dim>
struct MpmState {
  Particles<dim> particles;
  SparseGrid<dim> grid;
  ParticleBuckets<dim> buckets;
  Kernel kernel = QuadraticBSpline{};
  TransferScheme transfer;
  Vec<dim> gravity = Vec<dim>::Zero();  //!< [m/s^2]
  double time = 0.0;                    //!< [s]
  double dt = 0.0;                      //!< step being taken [s]
  double dt_limit = 1e300;              //!< largest step allowed now (frame end) [s]
  Index step = 0;
};

//! An empty state for `settings`: the grid sized to the domain (with its periodic axes),
//! kernel, transfer and gravity.
template <int dim>
MpmState<dim> initial_state(const SceneSettings<dim>& settings) {
  MpmState<dim> s;
  s.grid = SparseGrid<dim>(settings.domain_lo, settings.domain_hi, settings.dx, settings.periodic);
  s.kernel = settings.kernel;
  s.transfer = settings.transfer;
  s.gravity = settings.gravity;
  return s;
}

//! A particle phase of a state, seen by code that treats every phase alike (the Runner's
//! output, diagnostics and checkpoints). A single-phase state has one phase, unnamed (""); a
//! state of several (libcoupling's CoupledState) names each one and supplies its own
//! `phases` function, found by argument-dependent lookup.
template <int dim>
struct PhaseRef {
  std::string name;
  Particles<dim>* particles = nullptr;
  const SparseGrid<dim>* grid = nullptr;
  //! Drawn coloured by output.color_by in previews; false: drawn in a plain tint beneath the
  //! coloured phases (the fluid around the grains).
  bool coloured = true;
};

template <int dim>
std::vector<PhaseRef<dim>> phases(MpmState<dim>& s) {
  return {{"", &s.particles, &s.grid, true}};
}

}  // namespace mpm
