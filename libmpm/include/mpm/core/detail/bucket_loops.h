#pragma once
//! The two loop skeletons every transfer is built from (internal; used by libmpm and libfluid).
//!
//! scatter: per colour, buckets in parallel; each bucket accumulates Ch values per node into
//! a (2B)^dim scratch patch and then adds the patch into the grid channels.
//! gather:  buckets in parallel; each bucket copies the patch of Ch grid values per node into
//! scratch, then visits its particles.
//! The *_buckets forms hand the body a bucket's particle range, the plain forms one particle.
//! The per-particle body sees a Stencil: 1D weights per axis and a patch-local node offset.
//! The scalar type T of channels, patch and stencil is double for the library; the skeletons
//! are scalar-generic so a single-precision path can reuse them (bench/bench_transfer.cpp).
#include <mpm/core/kernels.h>
#include <mpm/core/particle_buckets.h>
#include <mpm/core/sparse_grid.h>

#include <tbb/parallel_for.h>

#include <array>

namespace mpm::detail {

//! One channel of grid storage: value of node k is data[k * stride + offset].
template <class T>
struct BasicChannelView {
  T* data;
  int stride;
  int offset;
};
using ChannelView = BasicChannelView<double>;

template <int dim>
constexpr int patch_width = 2 * SparseGrid<dim>::block_size;
template <int dim>
constexpr int patch_nodes = ipow(patch_width<dim>, dim);

//! Kernel weights of one particle relative to the patch of its bucket.
template <int dim, int S, class T = double>
struct Stencil {
  using VecT = Eigen::Matrix<T, dim, 1>;
  T w[dim][S];       //!< N(r) per axis
  T dw[dim][S];      //!< dN/dxi per axis [1/cell] (left unset by compute<false>)
  T rel[dim][S];     //!< node minus particle position per axis [cells]
  int patch_offset;  //!< patch index of the first stencil node

  template <bool gradient = true, class K>
  void compute(const K& kernel, const VecT& xi, const IVec<dim>& patch_origin) {
    patch_offset = 0;
    int stride = 1;
    for (int a = 0; a < dim; ++a) {
      int base;
      double wa[S], dwa[S];
      kernel(static_cast<double>(xi[a]), base, wa, dwa);
      for (int k = 0; k < S; ++k) {
        w[a][k] = static_cast<T>(wa[k]);
        if constexpr (gradient) dw[a][k] = static_cast<T>(dwa[k]);
        rel[a][k] = static_cast<T>(base + k) - xi[a];
      }
      patch_offset += (base - patch_origin[a]) * stride;
      stride *= patch_width<dim>;
    }
  }

  //! 1 / D_p per axis [1/cells^2], D_p = sum_i w_ip (x_i - x_p)^2 (APIC inertia, diagonal for
  //! tensor-product kernels because of linear reproduction). One division for all axes,
  //! 1/D_a = prod_{b != a} D_b / prod_b D_b; scalar code, as a vector built element by element
  //! and read back whole would stall store forwarding.
  void inverse_inertia(T (&inv_D)[dim]) const {
    T D[dim], prod = 1;
    for (int a = 0; a < dim; ++a) {
      D[a] = 0;
      for (int k = 0; k < S; ++k) D[a] += w[a][k] * rel[a][k] * rel[a][k];
      prod *= D[a];
    }
    const T inv_prod = 1 / prod;
    for (int a = 0; a < dim; ++a) {
      inv_D[a] = inv_prod;
      for (int b = 0; b < dim; ++b)
        if (b != a) inv_D[a] *= D[b];
    }
  }

  //! Calls fn(patch index, weight, gradient [1/cell], node - particle [cells]) for S^dim nodes.
  template <class Fn>
  void for_each_node(Fn&& fn) const {
    constexpr int W = patch_width<dim>;
    if constexpr (dim == 2) {
      for (int j = 0; j < S; ++j)
        for (int i = 0; i < S; ++i) {
          const VecT grad(dw[0][i] * w[1][j], w[0][i] * dw[1][j]);
          fn(patch_offset + i + W * j, w[0][i] * w[1][j], grad, VecT(rel[0][i], rel[1][j]));
        }
    } else {
      for (int k = 0; k < S; ++k)
        for (int j = 0; j < S; ++j) {
          const T wjk = w[1][j] * w[2][k];
          for (int i = 0; i < S; ++i) {
            const VecT grad(dw[0][i] * wjk, w[0][i] * dw[1][j] * w[2][k], w[0][i] * w[1][j] * dw[2][k]);
            fn(patch_offset + i + W * (j + W * k), w[0][i] * wjk, grad, VecT(rel[0][i], rel[1][j], rel[2][k]));
          }
        }
    }
  }
};

//! Patch index (relative to the patch's first node) of node l of a block: the block's
//! lexicographic node order mapped onto the wider patch rows. A table, so the patch <-> grid
//! copies do no index arithmetic per node.
template <int dim>
constexpr std::array<int, SparseGrid<dim>::nodes_per_block> block_to_patch = [] {
  constexpr int B = SparseGrid<dim>::block_size;
  std::array<int, SparseGrid<dim>::nodes_per_block> t{};
  for (int l = 0; l < SparseGrid<dim>::nodes_per_block; ++l) {
    int patch = 0, stride = 1, rest = l;
    for (int a = 0; a < dim; ++a) {
      patch += (rest % B) * stride;
      rest /= B;
      stride *= patch_width<dim>;
    }
    t[l] = patch;
  }
  return t;
}();

//! The most nodes per axis a stencil of the library's kernels spans (the cubic B-spline's).
inline constexpr int max_support = 4;

//! The patch nodes a `support`-node stencil of a bucket's particles can reach, per corner block
//! of the patch: the stencils start in the bucket's block, so on every axis the patch nodes
//! [0, B + support - 1) (for the quadratic kernels 216 of the 512 nodes in 3D). Per corner, the
//! count and the nodes as (patch index, index in the block), in the block's storage order.
template <int dim, int support>
struct PatchReach {
  static constexpr int B = SparseGrid<dim>::block_size;
  static_assert(support >= 1 && support <= B + 1);
  std::array<int, 1 << dim> count{};
  std::array<std::array<int, SparseGrid<dim>::nodes_per_block>, 1 << dim> patch{}, local{};
};
template <int dim, int support>
constexpr PatchReach<dim, support> patch_reach = [] {
  constexpr int B = SparseGrid<dim>::block_size;
  PatchReach<dim, support> r;
  for (int corner = 0; corner < (1 << dim); ++corner)
    for (int l = 0; l < SparseGrid<dim>::nodes_per_block; ++l) {
      bool reached = true;
      for (int a = 0, rest = l; a < dim; ++a, rest /= B)
        reached = reached && rest % B < (((corner >> a) & 1) ? support - 1 : B);
      if (!reached) continue;
      int corner_patch = 0;
      for (int a = 0, stride = 1; a < dim; ++a, stride *= patch_width<dim>)
        corner_patch += ((corner >> a) & 1) * B * stride;
      const int i = r.count[corner]++;
      r.patch[corner][i] = corner_patch + block_to_patch<dim>[l];
      r.local[corner][i] = l;
    }
  return r;
}();

//! Calls fn(patch index, storage index) for every node of the patch of the bucket whose first
//! block is `block` that a `support`-node stencil of its particles can reach (PatchReach).
template <int dim, int support = max_support, class Fn>
void for_each_patch_node(const SparseGrid<dim>& grid, BlockKey block, Fn&& fn) {
  constexpr int B = SparseGrid<dim>::block_size;
  constexpr const PatchReach<dim, support>& reach = patch_reach<dim, support>;
  const IVec<dim> origin = grid.block_coord(block) * B;
  for (int corner = 0; corner < (1 << dim); ++corner) {
    if (reach.count[corner] == 0) continue;
    IVec<dim> corner_node = origin;
    for (int a = 0; a < dim; ++a) corner_node[a] += ((corner >> a) & 1) * B;
    const std::size_t first =
        static_cast<std::size_t>(grid.slot(grid.block_id(corner_node))) * SparseGrid<dim>::nodes_per_block;
    for (int i = 0; i < reach.count[corner]; ++i)
      fn(reach.patch[corner][i], first + static_cast<std::size_t>(reach.local[corner][i]));
  }
}

//! Particle coordinate in cells (CellMap) and the first node of the bucket's patch.
template <int dim>
struct PatchFrame {
  IVec<dim> origin;
  CellMap<dim> map;
  PatchFrame(const SparseGrid<dim>& grid, BlockKey block)
      : origin(grid.block_coord(block) * SparseGrid<dim>::block_size), map(grid) {}
  template <class T>
  Eigen::Matrix<T, dim, 1> cells(const Eigen::Matrix<T, dim, 1>& x) const {
    return map(x);
  }
};

//! Loops over buckets of fewer particles than this run on the calling thread: waking the
//! workers costs tens of microseconds a loop, more than the work (an adaptive grid's levels).
inline constexpr std::size_t serial_below_particles = 2048;

//! body(range) over [0, n) with grain `grain`: on the calling thread when `serial`.
template <class I, class Body>
void for_each_range(I n, I grain, bool serial, Body&& body) {
  if (serial)
    body(tbb::blocked_range<I>(0, n, grain));
  else
    tbb::parallel_for(tbb::blocked_range<I>(0, n, grain), body);
}

//! bucket_body(first, last, const PatchFrame&, T* patch) adds Ch values per node of the
//! particles with indices [first, last) (a range of ParticleBuckets::particle: one bucket)
//! into patch[node * Ch + c]; the sums are added into `channels` afterwards. The particles'
//! stencils span at most `support` nodes per axis.
template <int dim, int Ch, int support = max_support, class T, class BucketBody>
void scatter_buckets(const SparseGrid<dim>& grid, const ParticleBuckets<dim>& buckets,
                     const std::array<BasicChannelView<T>, Ch>& channels, BucketBody&& bucket_body) {
  const bool serial = buckets.particle.size() < serial_below_particles;
  for (const std::vector<int>& same_color : buckets.by_color) {
    for_each_range(same_color.size(), std::size_t{4}, serial, [&](const tbb::blocked_range<std::size_t>& range) {
      alignas(64) std::array<T, patch_nodes<dim> * Ch> patch;
      for (std::size_t r = range.begin(); r != range.end(); ++r) {
        const int b = same_color[r];
        patch.fill(T(0));
        bucket_body(buckets.particle.data() + buckets.begin[b], buckets.particle.data() + buckets.begin[b + 1],
                    PatchFrame<dim>(grid, buckets.block[b]), patch.data());
        for_each_patch_node<dim, support>(grid, buckets.block[b], [&](int node, std::size_t k) {
          for (int c = 0; c < Ch; ++c)
            channels[c].data[k * channels[c].stride + channels[c].offset] += patch[node * Ch + c];
        });
      }
    });
  }
}

//! scatter_buckets with a body per particle: body(p, const PatchFrame&, T* patch).
template <int dim, int Ch, class T, class Body>
void scatter(const SparseGrid<dim>& grid, const ParticleBuckets<dim>& buckets,
             const std::array<BasicChannelView<T>, Ch>& channels, Body&& body) {
  scatter_buckets<dim, Ch>(
      grid, buckets, channels,
      [&](const std::uint32_t* first, const std::uint32_t* last, const PatchFrame<dim>& f, T* patch) {
        for (const std::uint32_t* p = first; p != last; ++p) body(*p, f, patch);
      });
}

//! bucket_body(first, last, const PatchFrame&, const T* patch) reads Ch values per node for
//! the particles with indices [first, last) (one bucket), whose stencils span at most `support`
//! nodes per axis (the other patch values are left unset).
template <int dim, int Ch, int support = max_support, class T, class BucketBody>
void gather_buckets(const SparseGrid<dim>& grid, const ParticleBuckets<dim>& buckets,
                    const std::array<BasicChannelView<T>, Ch>& channels, BucketBody&& bucket_body) {
  const bool serial = buckets.particle.size() < serial_below_particles;
  for_each_range(buckets.count(), 4, serial, [&](const tbb::blocked_range<int>& range) {
    alignas(64) std::array<T, patch_nodes<dim> * Ch> patch;
    for (int b = range.begin(); b != range.end(); ++b) {
      for_each_patch_node<dim, support>(grid, buckets.block[b], [&](int node, std::size_t k) {
        for (int c = 0; c < Ch; ++c)
          patch[node * Ch + c] = channels[c].data[k * channels[c].stride + channels[c].offset];
      });
      bucket_body(buckets.particle.data() + buckets.begin[b], buckets.particle.data() + buckets.begin[b + 1],
                  PatchFrame<dim>(grid, buckets.block[b]), patch.data());
    }
  });
}

//! gather_buckets with a body per particle: body(p, const PatchFrame&, const T* patch).
template <int dim, int Ch, class T, class Body>
void gather(const SparseGrid<dim>& grid, const ParticleBuckets<dim>& buckets,
            const std::array<BasicChannelView<T>, Ch>& channels, Body&& body) {
  gather_buckets<dim, Ch>(
      grid, buckets, channels,
      [&](const std::uint32_t* first, const std::uint32_t* last, const PatchFrame<dim>& f, const T* patch) {
        for (const std::uint32_t* p = first; p != last; ++p) body(*p, f, patch);
      });
}

//! Views of a scalar channel and of the components of a vector channel.
template <class T>
BasicChannelView<T> scalar_view(std::vector<T>& c) {
  return {c.data(), 1, 0};
}
//! For the gathers, which only read through the view.
template <class T>
BasicChannelView<T> scalar_view(const std::vector<T>& c) {
  return scalar_view(const_cast<std::vector<T>&>(c));
}
template <int dim, class T>
BasicChannelView<T> component_view(std::vector<Eigen::Matrix<T, dim, 1>>& c, int a) {
  return {reinterpret_cast<T*>(c.data()), dim, a};
}
template <int dim, class T>
BasicChannelView<T> component_view(const std::vector<Eigen::Matrix<T, dim, 1>>& c, int a) {
  return component_view<dim, T>(const_cast<std::vector<Eigen::Matrix<T, dim, 1>>&>(c), a);
}

}  // namespace mpm::detail
