#pragma once
//! Particle types matched to grid levels (Gao et al. 2017, sec. 7.1): a particle of type q
//! stands for a sub-cell of a level-q cell and carries a GIMP box of side dx_q, so that on its
//! own level it transfers with the quadratic B-spline. The type is the particle channel
//! "level", written in every frame (ParaView colours particles by it) and in checkpoints.
#include <mpm/adaptive/cell_tree.h>
#include <mpm/core/particles.h>

#include <cstdint>
#include <limits>
#include <vector>

namespace mpm::adaptive {

inline constexpr const char* kParticleLevel = "level";

//! Declares the "level" channel (initial value: the finest level of `tree`) and returns it.
template <int dim>
std::vector<std::uint16_t>& add_level_channel(Particles<dim>& particles, const CellTree<dim>& tree);

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
                                                 double fine_volume, int points_per_axis, int surface_steps = 0);

//! Manhattan distance, in lattice steps of spacing h [m], from each of the particles (on the
//! lattice x = (i + 1/2) h) to the nearest lattice site that holds none: 1 on the surface.
template <int dim>
std::vector<int> lattice_surface_distance(const std::vector<Vec<dim>>& x, double h);

//! Manhattan depth of each of the lattice sites `sites` (repeats allowed) in the set they form:
//! the fewest face steps to a site outside the set (1 for a site with an empty face neighbour).
//! Sites deeper than max_depth get max_depth + 1 (the search stops there).
template <int dim>
std::vector<int> manhattan_depth(const std::vector<IVec<dim>>& sites,
                                 int max_depth = std::numeric_limits<int>::max() - 1);

}  // namespace mpm::adaptive
