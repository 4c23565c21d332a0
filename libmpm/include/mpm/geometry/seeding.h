#pragma once
//! Initial particle positions on a lattice aligned to the global grid.
//!
//! A cell of spacing dx (grid nodes at integer multiples of dx) holds particles_per_cell = k^dim
//! particles at the centres of its k^dim sub-cells, x = (i + 1/2) dx/k. Because the lattice is
//! global, bodies seeded side by side tile without gap or overlap, and every particle stands
//! for the volume of its sub-cell: V_p = dx^dim / particles_per_cell (particle_volume()).
//! Jitter moves each particle uniformly within +-jitter/2 of a sub-spacing along every axis, so
//! it stays in its sub-cell; the random numbers come from std::mt19937_64 with explicit
//! conversion to [0, 1), so a seed gives the same particles on every platform.
#include <mpm/core/types.h>
#include <mpm/geometry/level_set.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace mpm::geometry {

//! k with k^dim == particles_per_cell; throws InputError when there is none.
template <int dim>
int lattice_points_per_axis(int particles_per_cell);

//! Volume each seeded particle stands for [m^dim].
template <int dim>
double particle_volume(double dx, int particles_per_cell);

//! The lattice points with lo <= x < hi (half-open, so adjacent boxes tile) for which
//! inside(x) holds, tested before jitter; jitter in [0, 1) is a fraction of the sub-spacing dx/k.
//! Throws InputError on dx <= 0, a particles_per_cell that is no k^dim, or a jitter out of range.
template <int dim>
std::vector<Vec<dim>> seed_lattice(const Vec<dim>& lo, const Vec<dim>& hi, double dx, int particles_per_cell,
                                   double jitter, std::uint64_t seed,
                                   const std::function<bool(const Vec<dim>&)>& inside);

//! The box [lo, hi).
template <int dim>
std::vector<Vec<dim>> seed_box(const Vec<dim>& lo, const Vec<dim>& hi, double dx, int particles_per_cell, double jitter,
                               std::uint64_t seed);

//! The ball |x - center| < radius.
template <int dim>
std::vector<Vec<dim>> seed_sphere(const Vec<dim>& center, double radius, double dx, int particles_per_cell,
                                  double jitter, std::uint64_t seed);

//! The interior phi < 0 of a level set (e.g. a closed mesh; in 2D its section z = slice_z).
template <int dim>
std::vector<Vec<dim>> seed_level_set(const LevelSetShape<dim>& shape, double dx, int particles_per_cell, double jitter,
                                     std::uint64_t seed);

}  // namespace mpm::geometry
