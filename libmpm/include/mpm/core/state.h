#pragma once
//! The state a single-phase MPM pipeline advances: one particle set on one sparse grid, or on
//! the levels of an adaptive grid (mpm/adaptive/) when the scene has the key `adaptive`.
#include <mpm/adaptive/adaptive_grid.h>
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/particles.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/sparse_grid.h>
#include <mpm/core/transfer.h>
#include <mpm/domains/particle_domains.h>

#include <optional>
#include <string>
#include <vector>

namespace mpm {

template <int dim>
struct MpmState {
  Particles<dim> particles;
  SparseGrid<dim> grid;  //!< the uniform grid (unused on an adaptive grid)
  //! The adaptive grid, in place of `grid`; absent on a uniform scene, which builds none of it.
  std::optional<adaptive::AdaptiveGrid<dim>> adaptive;
  //! The particles' domains (mpm/domains/), through which they reach the grid; absent unless the
  //! scene has the key `particle_domains`.
  std::optional<domains::ParticleDomains<dim>> domains;
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

//! The grids that the grid stages update: the uniform grid, or every level of the adaptive one
//! (State: MpmState<dim> or const MpmState<dim>).
template <class State>
auto grid_levels(State& s) {
  std::vector<decltype(&s.grid)> levels;
  if (!s.adaptive) levels.push_back(&s.grid);
  for (int n = 0; s.adaptive && n < s.adaptive->levels(); ++n) levels.push_back(&s.adaptive->level(n));
  return levels;
}

//! The finest grid spacing of the state [m]: the CFL limit of the time step.
template <int dim>
double finest_dx(const MpmState<dim>& s) {
  return s.adaptive ? s.adaptive->tree().dx(s.adaptive->tree().finest()) : s.grid.dx();
}

//! A particle phase of a state, seen by code that treats every phase alike (the Runner's
//! output, diagnostics and checkpoints). A single-phase state has one phase, unnamed (""); a
//! state of several (libcoupling's CoupledState) names each one and supplies its own
//! `phases` function, found by argument-dependent lookup.
template <int dim>
struct PhaseRef {
  std::string name;
  Particles<dim>* particles = nullptr;
  std::vector<const SparseGrid<dim>*> grids;  //!< its grid, or the levels of its adaptive grid
  //! Drawn coloured by output.color_by in previews; false: drawn in a plain tint beneath the
  //! coloured phases (the fluid around the grains).
  bool coloured = true;
  //! Memory of the grid's indexing tables besides its fields [B]: the particle buckets, and on
  //! an adaptive grid its tree, ghost tables and transfer lists (index_bytes below).
  std::size_t index_bytes = 0;
};

template <int dim>
std::size_t index_bytes(const MpmState<dim>& s) {
  return s.buckets.memory_bytes() + (s.adaptive ? s.adaptive->index_bytes() : 0) +
         (s.domains ? s.domains->memory_bytes() : 0);
}

//! What a restart needs of the state besides its particles and the stages' carried data: the
//! domain corners (stored in checkpoints beside the stages' data; runner_impl.h).
template <int dim>
CarriedData carried_state(const MpmState<dim>& s) {
  return s.domains ? domains::carried(*s.domains) : CarriedData{};
}
template <int dim>
void restore_state(MpmState<dim>& s, const CarriedData& data) {
  if (s.domains) domains::restore(*s.domains, data);
}

template <int dim>
std::vector<PhaseRef<dim>> phases(MpmState<dim>& s) {
  return {{"", &s.particles, grid_levels(std::as_const(s)), true, index_bytes(s)}};
}

}  // namespace mpm
