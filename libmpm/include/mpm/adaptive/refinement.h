#pragma once
//! Static refinement of an adaptive scene (Gao et al. 2017, sec. 7.1), read from the scene's
//! `adaptive` key:
//!
//!   adaptive:
//!     levels: 3                  # [1, 6]; grid.dx is the finest spacing, dx_0 = dx 2^(levels-1)
//!     refine:                    # regions refined to `level` (default: the finest)
//!       - {box: {lo: [0.2, 0.1], hi: [0.5, 0.3]}, level: 2}
//!       - {near_colliders: 0.02}   # cells within 0.02 m of a collider surface
//!     surface_band: 0.02         # bodies keep their finest particles within 0.02 m of their
//!                                #   surface; the others are regrouped to the leaves' levels
//!     follow_particles: true     # every step, refine the cells that hold a particle of a finer
//!                                #   type (the grid follows moving fine particles, sec. 7.1)
//!     padding: true              # and the cells one coarser cell around them that hold no
//!                                #   coarser particle (refine_around_particles)
//!     resample:                  # split and merge particles by their distance from the free
//!       d_small: 0.005           #   surface (resampling.h, sec. 7.2) [m]: nothing within d_small,
//!       d_medium: 0.01           #   split coarse particles up to d_medium, merge fine ones
//!       d_large: 0.02            #   beyond d_large; 0 <= d_small < d_medium < d_large
//!       every: 1                 #   resample every this many steps, [1, 1000000]
//!       max_travel: 0.0025       #   or instead once the particles may have travelled this far
//!                                #   since the last resampling [m], (0, (d_medium - d_small) / 2]
//!     surface_walls: all         # closed walls that count as surface for surface_band and the
//!                                #   resampling: none, rough (sticky or with friction), all
//!
//! Without the key a scene is uniform and builds nothing of the adaptive grid.
#include <mpm/adaptive/cell_tree.h>
#include <mpm/adaptive/resampling.h>
#include <mpm/core/config.h>
#include <mpm/core/scene_settings.h>
#include <mpm/geometry/collider.h>

#include <optional>
#include <vector>

namespace mpm::adaptive {

template <int dim>
struct RefinementRegion {
  enum class Kind { box, near_colliders } kind = Kind::box;
  Vec<dim> lo = Vec<dim>::Zero(), hi = Vec<dim>::Zero();  //!< box [m]
  double distance = 0.0;                                  //!< near_colliders: band width [m]
  int level = 0;                                          //!< target level
};

template <int dim>
struct RefinementSettings {
  int levels = 1;
  std::vector<RefinementRegion<dim>> regions;
  double surface_band = 0.0;  //!< [m]
  bool follow_particles = true;
  bool padding = true;  //!< refine_around_particles' padding
  //! Which closed walls of the domain count as surface for the surface band and the
  //! resampling's distance (the material continues through the others).
  SurfaceWalls surface_walls = SurfaceWalls::all;
  std::optional<ResampleSettings> resample;  //!< dynamic refinement by particle resampling
  //! Coarsest spacing dx_0 = dx 2^(levels-1) [m] for the finest spacing dx.
  double coarsest_dx(double finest_dx) const { return finest_dx * static_cast<double>(1 << (levels - 1)); }
};

//! The `adaptive` key of `scene`, or nothing when absent. Fails through Config (file, line,
//! key, value, accepted range) on levels out of range, boxes outside the domain or inverted,
//! region levels out of range, a periodic domain, a kernel other than quadratic, resampling distances out of order or
//! resampling without follow_particles or with one level.
template <int dim>
std::optional<RefinementSettings<dim>> parse_refinement(const Config& scene, const SceneSettings<dim>& settings);

//! The number of levels the scene's `adaptive` key asks for (1 without the key), validated as
//! parse_refinement does: apps size their wall layers with it before the domain is known.
int levels_of(const Config& scene);

//! Bytes the tree holds per refined cell: a key and a value in a hash table at most half full,
//! after growth by doubling.
inline constexpr double kBytesPerRefinedCell = 48.0;

//! Refuses, through `scene` (file, line, key, value), a static refinement whose tree would not
//! take more than half of the memory that still fits (core/memory_budget.h), before anything is
//! allocated: counts the cells each region refines on its own (overlaps twice: an upper
//! bound), and stops counting as soon as the sum is over.
template <int dim>
void check_refinement_memory(const Config& scene, const RefinementSettings<dim>& refinement,
                             const SceneSettings<dim>& settings, const geometry::ColliderSet<dim>& colliders);

//! The tree over the scene's domain (rounded up to whole coarse cells), refined in every region.
//! The type-driven refinement comes on top of it, every step (stage 'refine').
template <int dim>
CellTree<dim> build_tree(const RefinementSettings<dim>& refinement, const SceneSettings<dim>& settings,
                         const geometry::ColliderSet<dim>& colliders);

//! Refines `tree` so that every particle (positions x, types `type`) lies in a leaf of at
//! least its type's level; with `padding`, also the cells of the next coarser level around
//! those of each level's particles that no coarser particle reaches (the fine region padded by
//! one coarser cell into empty space: no ghost nodes in the fine particles' stencils there).
template <int dim>
void refine_around_particles(CellTree<dim>& tree, const std::vector<Vec<dim>>& x,
                             const std::vector<std::uint16_t>& type, bool padding);

}  // namespace mpm::adaptive
