#pragma once
//! Sediment and fluid volume fractions on the sediment grid (LANS; docs/coupling.md).
//!
//! Each sediment particle occupies V_p = m_p / rho_s of grain material; spread by the MPM
//! weights over the node volumes V_i = dx^dim:
//!   phi_i = sum_p w_ip V_p / V_i,
//! so sum_i phi_i V_i = sum_p V_p (partition of unity: the sediment volume is conserved), and
//! phi_i = m_i / (rho_s V_i) with m_i the node mass of the same P2G. The fractions the
//! coupling uses are clamped:
//!   n_s = min(phi, 1 - n_min),   n_w = 1 - n_s >= n_min.
//! The floor n_min = 0.35 (default) is just below the fluid fraction of random close packing
//! of monodisperse spheres (n_s ~ 0.64): no real bed is denser, so the clamp acts only where
//! the kernel estimate overshoots (particles bunched within a cell, compressed continuum
//! sediment). It keeps the drag laws' n_w^-1 ... n_w^-3.7 and the projection's n_w bounded.
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/particles.h>
#include <mpm/core/sparse_grid.h>

#include <vector>

namespace coupling {

//! Default lower bound of the fluid fraction n_w [-] (upper bound 1 - it of n_s).
inline constexpr double default_min_fluid_fraction = 0.35;

struct VolumeFractions {
  std::vector<double> sediment;  //!< n_s per storage node, in [0, 1 - n_min]
  std::vector<double> fluid;     //!< n_w = 1 - n_s per storage node, in [n_min, 1]
};

//! phi_i (unclamped) per storage node of `grid` from the sediment particles, sorted into
//! `buckets` against `grid`; `sediment_density` rho_s [kg/m^3] > 0 of the grain material.
template <int dim>
void sediment_fraction(const mpm::Particles<dim>& sediment, const mpm::ParticleBuckets<dim>& buckets,
                       const mpm::Kernel& kernel, const mpm::SparseGrid<dim>& grid, double sediment_density,
                       std::vector<double>& phi);

//! n_s and n_w from phi with the floor `min_fluid` = n_min in (0, 1].
VolumeFractions clamp_fractions(const std::vector<double>& phi, double min_fluid = default_min_fluid_fraction);

//! Cell value of a node field: the mean of the 2^dim corners of the cell whose lower corner is
//! node `cell`, which is the exact cell average of the multilinear interpolant (the cell
//! average the semi-staggered divergence uses). Corners outside the allocated blocks count 0.
template <int dim>
double cell_average(const mpm::SparseGrid<dim>& grid, const std::vector<double>& node_values,
                    const mpm::IVec<dim>& cell);

}  // namespace coupling
