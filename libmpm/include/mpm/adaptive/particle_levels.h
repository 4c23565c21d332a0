#pragma once
//! Particle types matched to grid levels (Gao et al. 2017, sec. 7.1): a particle of type q
//! stands for a sub-cell of a level-q cell and carries a GIMP box of side dx_q, so that on its
//! own level it transfers with the quadratic B-spline. The type is the particle channel
//! "level", written in every frame (ParaView colours particles by it) and in checkpoints.
#include <mpm/adaptive/cell_tree.h>
#include <mpm/core/particles.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <vector>

namespace mpm::adaptive {

inline constexpr const char* kParticleLevel = "level";

//! Declares the "level" channel (initial value: the finest level of `tree`) and returns it.
template <int dim>
std::vector<std::uint16_t>& add_level_channel(Particles<dim>& particles, const CellTree<dim>& tree);

//! Where a lattice ends at solid walls: the sites before lo[a] or after hi[a] on axis a lie
//! beyond a wall and count as full, so a body against a wall has no surface there (the free
//! surface is where the material meets empty space, not its container). A full site beyond a
//! wall is its own mirror image's neighbour: for the L1 metric the mirror images of the empty
//! sites inside are never nearer than the sites themselves, so "full beyond the wall" is the
//! depth of the body mirrored through the wall. The default has no walls.
template <int dim>
struct LatticeWalls {
  IVec<dim> lo = IVec<dim>::Constant(std::numeric_limits<int>::min());
  IVec<dim> hi = IVec<dim>::Constant(std::numeric_limits<int>::max());
  bool beyond(const IVec<dim>& i) const { return (i.array() < lo.array()).any() || (i.array() > hi.array()).any(); }
};

//! Particles seeded on the finest level's lattice, regrouped to match the leaves: wherever
//! the full set of fine particles of a level-q sub-cell (spacing dx_q / k, k per axis per
//! cell) is present and the leaf there is of level <= q, those particles become one particle
//! of type q at their mean position with their summed volume; the others stay fine, and so do
//! the particles within `surface_steps` lattice steps (Manhattan distance) of an empty lattice
//! site: the body's surface band (Gao et al. 2017, sec. 7.1: fine particles near the free
//! surface, coarse ones inside). Mass and volume are conserved exactly.
template <int dim>
struct LevelledParticles {
  std::vector<Vec<dim>> x;
  std::vector<double> volume;
  std::vector<std::uint16_t> level;
};
template <int dim>
LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>& tree, const std::vector<Vec<dim>>& fine,
                                                 double fine_volume, int points_per_axis, int surface_steps = 0,
                                                 const LatticeWalls<dim>& walls = {});

//! Manhattan distance, in lattice steps of spacing h [m], from each of the particles (on the
//! lattice x = (i + 1/2) h) to the nearest lattice site that holds none and is not beyond
//! `walls`: 1 on the surface.
template <int dim>
std::vector<int> lattice_surface_distance(const std::vector<Vec<dim>>& x, double h,
                                          const LatticeWalls<dim>& walls = {});

//! Manhattan depth of each of the lattice sites `sites` (repeats allowed) in the set they form:
//! the fewest face steps to a site outside the set and not beyond `walls` (1 for a site with
//! such a face neighbour). Sites deeper than max_depth get max_depth + 1 (the result is capped
//! there).
template <int dim>
std::vector<int> manhattan_depth(const std::vector<IVec<dim>>& sites,
                                 int max_depth = std::numeric_limits<int>::max() - 1,
                                 const LatticeWalls<dim>& walls = {});

//! A dense box of lattice cells around a set of cells lo_cell..hi_cell, with a ring of empty
//! cells on every side (axis 0 fastest in flat()).
template <int dim>
struct LatticeBox {
  IVec<dim> lo, extent;
  LatticeBox(const IVec<dim>& lo_cell, const IVec<dim>& hi_cell)
      : lo(lo_cell.array() - 1), extent((hi_cell - lo_cell).array() + 3) {}
  double cells() const { return extent.template cast<double>().prod(); }
  std::size_t flat(const IVec<dim>& i) const {
    std::size_t f = 0;
    for (int a = dim - 1; a >= 0; --a) f = f * static_cast<std::size_t>(extent[a]) + (i[a] - lo[a]);
    return f;
  }
  //! max_depth + 1, or less where the ring bounds every depth: the transform's cap.
  int cap(int max_depth) const {
    return static_cast<int>(std::min<long long>(static_cast<long long>(max_depth) + 1, extent.sum()));
  }
  //! Whether a set of `count` cells is compact enough for a dense box.
  bool dense_for(std::size_t count) const { return cells() <= 8.0 * static_cast<double>(count) + 65536.0; }
};

//! manhattan_depth on a LatticeBox: `depth` (one per cell) holds 0 on empty cells and `cap` on
//! the set's; afterwards each cell holds min(fewest face steps to an empty cell, cap). The L1
//! metric is separable, so one forward and one backward sweep per axis give it exactly, the
//! lines of a sweep in parallel. The cells of the box beyond `walls` are set full first.
template <int dim>
void manhattan_transform(const LatticeBox<dim>& box, std::vector<int>& depth, int cap,
                         const LatticeWalls<dim>& walls = {});

}  // namespace mpm::adaptive
