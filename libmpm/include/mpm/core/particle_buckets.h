#pragma once
//! Particles ordered by the grid block that holds their first stencil node.
//!
//! Transfers walk one bucket (the particles of one block) at a time and accumulate into a
//! small scratch patch of (2B)^dim nodes that stays in L1 cache, then add the patch into the
//! 2^dim blocks it overlaps. Buckets whose blocks differ in parity ("colour") never touch the
//! same nodes, so each colour runs in parallel without atomics and the result does not depend
//! on the thread count.
//!
//! The order is an index (ParticleBuckets::particle). Between steps particles change
//! buckets only here and there, the index stays nearly sequential, and the transfers reach
//! the particles through it at the cost of sorted storage, so no channel is copied. Only a
//! scattered index (storage far from bucket order) makes every particle a cache miss, twice
//! per step; then the particles are moved into bucket order once (bench/bench_transfer.cpp).
#include <mpm/core/kernels.h>
#include <mpm/core/particles.h>
#include <mpm/core/sparse_grid.h>

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace mpm {

template <int dim>
struct ParticleBuckets {
  static constexpr int colors = 1 << dim;
  std::vector<std::uint32_t> particle;  //!< particle indices in bucket order
  std::vector<std::uint32_t> begin;     //!< bucket b holds particle[begin[b]] .. particle[begin[b+1] - 1]
  std::vector<BlockKey> block;          //!< key of the block of bucket b (SparseGrid::block_id)
  std::array<std::vector<int>, colors> by_color;

  int count() const { return static_cast<int>(block.size()); }
  std::size_t memory_bytes() const {
    std::size_t bytes =
        (particle.capacity() + begin.capacity()) * sizeof(std::uint32_t) + block.capacity() * sizeof(BlockKey);
    for (const std::vector<int>& c : by_color) bytes += c.capacity() * sizeof(int);
    return bytes;
  }
};

//! Position in cell units, xi = (x - origin) / dx, evaluated in the precision of x. The sort
//! and the transfers share this one expression, so both find the same stencil base even for
//! a particle exactly on a cell boundary.
template <int dim>
struct CellMap {
  Vec<dim> origin;  //!< [m]
  double inv_dx;    //!< [1/m]
  explicit CellMap(const SparseGrid<dim>& grid) : origin(grid.origin()), inv_dx(1.0 / grid.dx()) {}
  template <class T>
  Eigen::Matrix<T, dim, 1> operator()(const Eigen::Matrix<T, dim, 1>& x) const {
    return (x - origin.template cast<T>()) * static_cast<T>(inv_dx);
  }
};

//! First stencil node of a particle at x for `kernel` (floor of the kernel's base).
template <int dim>
IVec<dim> stencil_base(const SparseGrid<dim>& grid, const Kernel& kernel, const Vec<dim>& x);

//! Orders the particles by block (stable counting sort of an index), fills `buckets` and
//! allocates the grid blocks their stencils touch. The particles stay where they are unless
//! the index is scattered (storage order far from bucket order, e.g. freshly seeded or
//! shuffled particles): then they are stored anew in bucket order, once, and the index is the
//! identity. Throws NumericalError naming `stage`, the particle and its position if a
//! particle is not finite or its stencil leaves the grid. Returns true when the particles
//! were moved.
template <int dim>
bool sort_into_buckets(Particles<dim>& particles, const Kernel& kernel, SparseGrid<dim>& grid,
                       ParticleBuckets<dim>& buckets, const std::string& stage = "sort");

using MoveParticles = std::function<void(const std::vector<std::uint32_t>& order)>;

//! True when an index into particle storage is scattered: on average fewer than 8 particles
//! per run of consecutive storage indices, so reaching the particles through it misses the
//! cache at almost every particle and storing them anew in index order pays.
bool scattered(const std::vector<std::uint32_t>& index);

//! sort_into_buckets for positions in any storage and precision (T = double or float): when
//! the index is scattered, calls move(order) for the caller to store its particles anew in
//! bucket order (new index i holds old index order[i]); without `move` the index stays.
template <int dim, class T>
bool sort_into_buckets(const std::vector<Eigen::Matrix<T, dim, 1>>& x, const Kernel& kernel, SparseGrid<dim>& grid,
                       ParticleBuckets<dim>& buckets, const MoveParticles& move = {},
                       const std::string& stage = "sort");

//! For callers that keep their particles stored in bucket order: returns the permutation into
//! block order (new index i holds old index order[i]), empty when the particles are already
//! in order, and fills `buckets` for the particles after the caller has applied it.
template <int dim, class T>
std::vector<std::uint32_t> bucket_order(const std::vector<Eigen::Matrix<T, dim, 1>>& x, const Kernel& kernel,
                                        SparseGrid<dim>& grid, ParticleBuckets<dim>& buckets,
                                        const std::string& stage = "sort");

}  // namespace mpm
