#pragma once
//! Particle <-> grid transfers (paper sec. 3.2; APIC of Jiang et al. 2015).
//!
//! P2G:  m_i = sum_p w_ip m_p
//!       (m v)_i = sum_p w_ip m_p (v_p + C_p (x_i - x_p))          (C_p = 0 for PIC/FLIP)
//! G2P:  v_i^PIC = sum_i w_ip v_i,   B_p = sum_i w_ip v_i (x_i - x_p)^T,  C_p = B_p D_p^-1
//!       APIC:  v_p = v^PIC, C_p as above
//!       FLIP:  v_p = a (v_p + sum_i w_ip (v_i - v_i^old)) + (1 - a) v^PIC,  C_p = 0
//!       x_p += dt v^PIC
//! Preconditions: particles sorted into `buckets` against `grid` (sort_into_buckets).
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace mpm {

//! An update of the particles with indices [first, last) (one bucket) that a transfer runs
//! right after it has visited them; called in parallel on disjoint lists.
using ParticleGroupUpdate = std::function<void(const std::uint32_t* first, const std::uint32_t* last)>;

struct TransferScheme {
  enum class Type { apic, flip };
  Type type = Type::apic;
  double flip_ratio = 0.95;  //!< a in [0, 1] for Type::flip; 0 is PIC
  bool uses_old_velocity() const { return type == Type::flip; }
};

//! Particles in buckets and the kernel they transfer with. The scatters below also take several
//! groups into one grid: an adaptive level's own particles and those whose GIMP box is one of
//! its cells transfer with different weights.
template <int dim>
struct BucketGroup {
  const ParticleBuckets<dim>* buckets;
  Kernel kernel;
};

//! The stresses S_p [N m] a scatter spreads, indexed like the particles: S_p = weight_p tau_p,
//! or tau_p where no weights are given. The solid's P2G passes the return map's Kirchhoff stress
//! cache with the weights V_p^0 and so forms no per-particle copy of V_p^0 tau_p (one pass over
//! the particles less per step, docs/performance.md).
template <int dim>
struct ParticleStress {
  const Mat<dim>* tau = nullptr;
  const double* weight = nullptr;
  std::size_t count = 0;  //!< entries of tau and weight (0 when their sizes differ)

  ParticleStress() = default;
  //! S_p = S[p] (nullptr: no stress). Implicit: a scatter's callers pass &S.
  ParticleStress(const std::vector<Mat<dim>>* S) : tau(S ? S->data() : nullptr), count(S ? S->size() : 0) {}
  ParticleStress(const std::vector<Mat<dim>>& stress, const std::vector<double>& weights)
      : tau(stress.data()), weight(weights.data()), count(stress.size() == weights.size() ? stress.size() : 0) {}

  explicit operator bool() const { return tau != nullptr; }
  Mat<dim> operator[](std::size_t p) const { return weight ? Mat<dim>(weight[p] * tau[p]) : tau[p]; }
};

//! Accumulates node mass and momentum (into grid.velocity); zeroes both first. With
//! `stress` (S_p per particle, as in stress_to_grid_forces) the same pass also forms
//! grid.force = - sum_p S_p grad w_ip: one scatter instead of two, with the sums of the two,
//! bit for bit. With `impulse_dt` > 0 as well, the momentum takes the impulse
//! -dt sum_p S_p grad w_ip instead and grid.force is released: a grid update's
//! v = (p + dt f) / m without a force channel (3 fewer values per node to scatter and keep),
//! equal to p / m + (dt / m) f up to round-off. Not for FLIP, whose v_old = p / m (an Error).
template <int dim>
void particles_to_grid(const Particles<dim>& particles, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                       const TransferScheme& scheme, SparseGrid<dim>& grid,
                       std::type_identity_t<ParticleStress<dim>> stress = {}, double impulse_dt = 0.0);
//! The same for the particles of several groups, one after the other.
template <int dim>
void particles_to_grid(const Particles<dim>& particles, std::span<const BucketGroup<dim>> groups,
                       const TransferScheme& scheme, SparseGrid<dim>& grid,
                       std::type_identity_t<ParticleStress<dim>> stress = {}, double impulse_dt = 0.0);

//! Divides momentum by mass (nodes without mass get zero velocity); keeps a copy in
//! grid.velocity_old when the scheme needs it.
template <int dim>
void momentum_to_velocity(SparseGrid<dim>& grid, const TransferScheme& scheme);

//! Updates v_p, C_p from grid.velocity (and velocity_old for FLIP) and advects x_p by dt. With
//! `F` (a deformation gradient per particle) the same gather also updates
//! F_p = (I + dt grad v_p) F_p, grad v_p = sum_i v_i (grad w_ip)^T before the advection. With
//! `then`, each bucket's particles go through it right after their gather.
template <int dim>
void grid_to_particles(Particles<dim>& particles, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                       const TransferScheme& scheme, const SparseGrid<dim>& grid, double dt,
                       std::vector<Mat<dim>>* F = nullptr, const ParticleGroupUpdate* then = nullptr);

//! out_i = sum_p w_ip values[p] on every node (out sized to the grid's node storage, zeroed
//! first): a per-particle quantity carried to the grid with the P2G weights (a volume fraction).
template <int dim>
void scalar_to_grid(const std::vector<double>& values, const Particles<dim>& particles,
                    const ParticleBuckets<dim>& buckets, const Kernel& kernel, const SparseGrid<dim>& grid,
                    std::vector<double>& out);

//! out_p = sum_i w_ip values_i for every particle: a node field (sized to the grid's node
//! storage) read at the particles with the G2P weights, the counterpart of scalar_to_grid.
template <int dim>
void grid_to_scalar(const std::vector<double>& values, const Particles<dim>& particles,
                    const ParticleBuckets<dim>& buckets, const Kernel& kernel, const SparseGrid<dim>& grid,
                    std::vector<double>& out);

//! grid.force_i = - sum_p S_p grad w_ip on every node (zeroed first), S_p = V_p^0 tau_p the
//! particle's volume-weighted Kirchhoff stress [N m]: the internal forces of an elastic solid, of
//! a weakly compressible fluid, of any stress carried by particles (Gao et al. 2017, eq. 1-2).
template <int dim>
void stress_to_grid_forces(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& particles,
                           const ParticleBuckets<dim>& buckets, const Kernel& kernel, SparseGrid<dim>& grid);
//! The same for the particles of several groups, one after the other.
template <int dim>
void stress_to_grid_forces(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& particles,
                           std::span<const BucketGroup<dim>> groups, SparseGrid<dim>& grid);

//! The same sum into any node array `out` (sized to the node storage): the force differential
//! of an implicit solve.
template <int dim>
void stress_to_nodes(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& particles,
                     const ParticleBuckets<dim>& buckets, const Kernel& kernel, const SparseGrid<dim>& grid,
                     std::vector<Vec<dim>>& out);

//! Velocity gradient grad v_p = sum_i v_i (grad w_ip)^T [1/s] for every particle.
template <int dim>
void velocity_gradient(const Particles<dim>& particles, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                       const SparseGrid<dim>& grid, std::vector<Mat<dim>>& grad_v);

//! The same gradient of any node field u (sized to the node storage): sum_i u_i (grad w_ip)^T.
template <int dim>
void node_field_gradient(const Particles<dim>& particles, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                         const SparseGrid<dim>& grid, const std::vector<Vec<dim>>& u, std::vector<Mat<dim>>& grad);

}  // namespace mpm
