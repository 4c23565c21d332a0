#pragma once
//! How evenly particles fill the inside of a body: the per-cell particle counts over the cells
//! well inside it, so that holes and streaks of empty space show as empty cells and a spread of
//! counts, and the free surface (where cells are partly full by nature) does not.
//!
//! Cells are those of the grid of spacing dx with nodes at origin + i dx. Let F be the cells
//! holding a particle. The inside is the morphological closing of F by the 3^dim box (fills
//! holes up to two cells wide), eroded once more (drops the surface layer):
//!   inside = erode(erode(dilate(F))),
//! i.e. the cells c whose every cell within Chebyshev distance 2 has a cell of F within
//! distance 1. Over the inside cells, with n_c particles each:
//!   count_cv     = std(n_c) / mean(n_c)  (population standard deviation);
//!   empty_share  = share of inside cells with n_c = 0 (holes);
//!   sparse_share = share with n_c <= mean / 4.
//! A lattice seeded with k^dim particles per cell gives count_cv = 0 and no empty cells.
#include <mpm/core/types.h>

#include <cstdint>
#include <vector>

namespace mpm::geometry {

struct ParticleSpacing {
  std::int64_t inside_cells = 0;
  double mean_count = 0.0;
  double count_cv = 0.0;
  double empty_share = 0.0;
  double sparse_share = 0.0;
};

//! The cells that hold a point of `excluding` (another phase, e.g. a sand bed with its pore water)
//! leave the inside after the closing and erosion: they are neither counted nor holes.
template <int dim>
ParticleSpacing particle_spacing(const std::vector<Vec<dim>>& x, const Vec<dim>& origin, double dx,
                                 const std::vector<Vec<dim>>& excluding = {});

}  // namespace mpm::geometry
