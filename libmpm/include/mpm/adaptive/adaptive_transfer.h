#pragma once
//! Particle <-> grid transfers on the adaptive grid through ghost nodes (Gao et al. 2017,
//! sec. 6.1, eq. 15), APIC (Jiang et al. 2015) or PIC/FLIP. Each particle transfers on its
//! transfer level with uniform GIMP weights w_kp; the weights on the real nodes are
//! w_ip = sum_k E_ik w_kp. With them, and with the real nodes' own positions x_i:
//!
//! P2G:  m_i = sum_p w_ip m_p,   (m v)_i = sum_p w_ip m_p (v_p + C_p (x_i - x_p))
//! G2P:  v_p = sum_i w_ip v_i,   B_p = sum_i w_ip v_i (x_i - x_p)^T,
//!       D_p = sum_i w_ip (x_i - x_p)(x_i - x_p)^T,  C_p = B_p D_p^-1
//!
//! D_p is the weights' own second moment (not dx^2/4: a particle near a level transition sees
//! nodes of several spacings), so an affine velocity field passes P2G -> G2P unchanged and
//! angular momentum is conserved. Preconditions: AdaptiveGrid::prepare for these particles.
#include <mpm/adaptive/adaptive_grid.h>
#include <mpm/core/particles.h>
#include <mpm/core/transfer.h>

namespace mpm::adaptive {

//! Mass and momentum (in `velocity`, as the uniform P2G) of the real nodes; ghosts pushed and
//! cleared. With `stress` the same scatter also forms the forces of stress_to_grid_forces (one
//! pass over particles and grid, as the uniform P2G), or with `impulse_dt` > 0 adds them to the
//! momentum as the impulse dt f (mpm::particles_to_grid).
template <int dim>
void particles_to_grid(const Particles<dim>& particles, const TransferScheme& scheme, AdaptiveGrid<dim>& grid,
                       std::type_identity_t<ParticleStress<dim>> stress = {}, double impulse_dt = 0.0);

//! velocity = momentum / mass on every level (velocity_old kept for FLIP).
template <int dim>
void momentum_to_velocity(AdaptiveGrid<dim>& grid, const TransferScheme& scheme);

//! force_i = - sum_p S_p grad w_ip on the real nodes (ghosts pushed), S_p = V_p^0 tau_p [N m].
template <int dim>
void stress_to_grid_forces(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& particles,
                           AdaptiveGrid<dim>& grid);

//! Fills the ghosts from the real nodes after the grid update; G2P reads them.
template <int dim>
void pull_velocities(AdaptiveGrid<dim>& grid, const TransferScheme& scheme);

//! Updates v_p and C_p (APIC) or v_p (FLIP, C_p = 0) and advects x_p by dt with v^PIC; with
//! `F`, also F_p = (I + dt grad v_p) F_p, grad v_p = sum_i v_i (grad w_ip)^T at x_p before the
//! advection (the uniform loops gather it with v and C, mpm::grid_to_particles). With `then`,
//! each group of particles goes through it once its v, x and F are final (C of the particles
//! near embedded ghosts is completed afterwards: `then` must not read C).
template <int dim>
void grid_to_particles(Particles<dim>& particles, const TransferScheme& scheme, const AdaptiveGrid<dim>& grid,
                       double dt, std::vector<Mat<dim>>* F = nullptr, const ParticleGroupUpdate* then = nullptr);

//! The weights of one particle on the real nodes: w_ip and grad w_ip [1/m] by (level, storage
//! index), summed over its ghosts. For tests and diagnostics; the transfers never build it.
template <int dim>
struct RealWeight {
  int level;
  Index index;
  double w;
  Vec<dim> grad;
};
template <int dim>
std::vector<RealWeight<dim>> real_weights(const AdaptiveGrid<dim>& grid, int level, double half_cells,
                                          const Vec<dim>& x);

}  // namespace mpm::adaptive
