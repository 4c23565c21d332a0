#pragma once
//! Particle resampling on an adaptive grid (Gao et al. 2017, sec. 7.1-7.2): fine particles near
//! the free surface, coarse ones inside, kept so while the material flows by splitting and
//! merging particles by their Manhattan distance d from the free surface.
//!
//! Distances. d is measured on the finest level's cells: a cell is occupied when a particle's
//! GIMP box (side dx_q / k for a particle of type q, k points per axis) overlaps it; d =
//! (n - 1/2) dx_finest for the cells n face steps from the nearest empty cell (n = 1 on the
//! surface). A particle takes the d of the cell it lies in. Cells beyond a closed wall that is
//! no surface (SurfaceWalls below) are full: the free surface is where the material meets
//! empty space, not a smooth container.
//!
//! Rules, for the transition t = 1, 2, ... between level finest - t + 1 and finest - t (t = 1:
//! finest and next), with the band widths growing as the cells do, s_t = 2^t - 1:
//!   - d <= d_small: nothing (a change near the surface is visible);
//!   - split a particle of level finest - t when d_small < d < s_t d_medium;
//!   - merge particles of level finest - t + 1 when d > s_t d_large;
//!   - between s_t d_medium and s_t d_large nothing (the hysteresis that keeps a particle from
//!     flip-flopping).
//! A particle several levels too coarse splits once per resampling step, one level at a time.
//!
//! Guards (sec. 7.2: "prohibited if the number of particles within a cell is either too large
//! or too small"): a particle splits only when its own level's cell holds between k^dim / 2 and
//! 2 k^dim particles of its level; a merge group, the particles of one level, material and
//! coarse sub-cell (side b = dx_{q-1} / k, nominally 2^dim particles), merges only when their
//! reference volumes sum to between 3/4 and 3/2 of b^dim. So every particle keeps at least 3/4
//! of its level's nominal volume, and the count stays below 4/3 of an all-fine body's: a guard
//! on the count alone let 2 particles merge into a light coarse particle that split into 4
//! lighter fine ones, and in a turning drum the count grew fifteenfold in 3 s.
//!
//! Split (type q -> q+1): 2^dim children at the centres of the sub-boxes of the parent's box
//! (offsets +-b/4 per axis, b = dx_q / k), the set turned by a random rotation (deterministic:
//! a hash of the step and the parent's index). Mass and volume are divided equally, every
//! other channel is copied, but the velocity: child i moves with the parent's APIC velocity
//! field there, v_i = v + C r_i. Mass, volume, the first moment sum m x and the linear momentum
//! are conserved exactly (sum r_i = 0). Angular momentum: sum m_i x_i x v_i = m x x v +
//! sum m_i r_i x C r_i, that is the parent's affine spin becomes orbital motion of the
//! children, m eps:(C S) with S = sum (m_i / m) r_i r_i^T = (b/4)^2 I; C is copied, so the
//! affine part is counted again in the children's own C (the APIC angular momentum of a
//! particle, m eps:(C D_p), scales with the particle's box: D_p of the children is that of
//! the finer level).
//!
//! Merge (group -> one particle of type q-1): mass and volume summed; position, velocity, C and
//! every other real channel the mass-weighted mean (so the mass centre and the linear momentum
//! are exact); a deformation channel (F^E) by average_deformation below. The children's spread
//! velocity sum m_i r_i x (v_i - v) is dropped: angular momentum changes by exactly that. A
//! split followed by the merge of its children returns the parent to round-off.
#include <mpm/adaptive/cell_tree.h>
#include <mpm/adaptive/particle_levels.h>
#include <mpm/core/particles.h>
#include <mpm/geometry/collider.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace mpm::adaptive {

//! Closed walls refined as a free surface is: none, the rough ones (sticky, or separate with
//! friction: the shear layer along them wants the fine cells) or all.
enum class SurfaceWalls { none, rough, all };

struct ResampleSettings {
  double d_small = 0.0;   //!< [m]
  double d_medium = 0.0;  //!< [m]
  double d_large = 0.0;   //!< [m]
  int every = 1;          //!< resample every `every` steps
  //! > 0: resample instead once the particles may have travelled this far [m] since the last
  //! resampling (the bound sum over steps of dt max_p |v_p|); at most (d_medium - d_small) / 2,
  //! so that no coarse particle comes nearer the surface than d_small before it is split.
  double max_travel = 0.0;
};

struct ResampleCounts {
  std::size_t split = 0;   //!< particles split
  std::size_t merged = 0;  //!< particles merged away (a group of n counts n)
  std::size_t groups = 0;  //!< particles created by merging
};

//! Manhattan distance [m] of each particle from the free surface, as described above, for
//! particles of types `level` with k = points_per_axis; cells farther than `max_distance` [m]
//! inside (the largest threshold in use) get a distance above it. The cells beyond `walls`
//! (on the finest cells of `tree`) are full: a wall is no free surface.
template <int dim>
std::vector<double> surface_distance(const CellTree<dim>& tree, const std::vector<Vec<dim>>& x,
                                     const std::vector<std::uint16_t>& level, int points_per_axis, double max_distance,
                                     const LatticeWalls<dim>& walls = {});

//! The closed walls of the domain that are no surface by `surface` (all but the rough ones for
//! SurfaceWalls::rough) on the lattice of spacing h [m] from `origin` (the finest cells of a
//! tree, or a seeding lattice): each wall where the material meets it, `thickness` inside the
//! domain's face; open walls bound nothing.
template <int dim>
LatticeWalls<dim> lattice_walls(const geometry::DomainWalls<dim>& walls, SurfaceWalls surface, const Vec<dim>& origin,
                                double h);

//! Splits and merges the particles of P (channel "level") by the rules above; `deformation`
//! names the Mat channels averaged by average_deformation on merge (the solid's "F"); `step`
//! seeds the split rotations. Particles that are not split or merged keep their order; the
//! buckets of the state must be rebuilt afterwards (a sort stage follows).
template <int dim>
ResampleCounts resample_particles(Particles<dim>& P, const CellTree<dim>& tree, int points_per_axis,
                                  const ResampleSettings& settings, const std::vector<std::string>& deformation,
                                  std::uint64_t step, const LatticeWalls<dim>& walls = {});

//! Splits particle p of type q < finest into 2^dim particles of type q+1, turned by `rotation`
//! (a proper rotation): p becomes the first child, the others are appended.
template <int dim>
void split_particle(Particles<dim>& P, std::size_t p, const CellTree<dim>& tree, int points_per_axis,
                    const Mat<dim>& rotation);

//! Merges the particles `group` (same level q > 0 and material) into one particle of type q-1
//! stored at group[0]; the others are flagged in `erase` (size P.size()) for
//! Particles::erase_flagged. `deformation`: as in resample_particles.
template <int dim>
void merge_particles(Particles<dim>& P, const std::vector<std::size_t>& group,
                     const std::vector<std::string>& deformation, std::vector<std::uint8_t>& erase);

//! The mass-weighted mean of deformation gradients (weights w >= 0, not all zero), after the
//! paper's SVD average, made well posed: each F_i = U_i Sigma_i V_i^T (math/svd.h, inverted F
//! with a negative last singular value) is split into its rotation R_i = U_i V_i^T and stretch
//! S_i = V_i Sigma_i V_i^T; the rotations are averaged as quaternions (the eigenvector of
//! sum w q q^T of the largest eigenvalue, Markley et al. 2007), the stretches arithmetically,
//! and F = R S. When all U_i and all V_i agree this is the paper's U mean(Sigma) V^T; averaging
//! U and V separately is not, because they are not unique (F = I has any U = V).
template <int dim>
Mat<dim> average_deformation(const std::vector<Mat<dim>>& F, const std::vector<double>& w);

//! A uniformly distributed proper rotation drawn from a counter-based hash of `key`.
template <int dim>
Mat<dim> random_rotation(std::uint64_t key);

}  // namespace mpm::adaptive
