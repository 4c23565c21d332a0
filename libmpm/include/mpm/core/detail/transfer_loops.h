#pragma once
//! The P2G and G2P loops of transfer.h (equations there) over any particle storage PS whose
//! channels x, v, C, mass hold scalar T: Particles<dim> (T = double) in the library, a
//! single-precision copy in bench/bench_transfer.cpp. Internal.
//!
//! The stencil is a tensor product, and the APIC node value is affine in the node offset,
//!   m_p (v_p + C_p (x_i - x_p)) = c_0 + sum_a rel_a c_{a+1},  c_0 = (m, m v), c_{a+1} = (0, m C e_a dx),
//! so both loops work one axis at a time with integer node offsets n_a = rel_a - rel_a[0]:
//! P2G (spread) steps the node value by c_{a+1} from node to node, G2P (collect) forms the
//! moments sum w v and sum w n_a v from the products w v by additions. A node then costs one
//! multiply and a few adds on its channels, where the textbook loop forms a weight product
//! and a matrix-vector product per node. Particles are set up in chunks (in_chunks).
//! spread and collect are forced inline: called, they pass the coefficients through memory.
//! G2P's bucket loop is compiled twice, for the build's baseline and for AVX2, and the CPU
//! picks one at run time (with_simd): the binary stays portable (-march=x86-64-v2).
#include <mpm/core/detail/bucket_loops.h>

#include <algorithm>
#include <cstring>
#include <type_traits>

namespace mpm::detail {

//! Asks for the cache lines of `object` ahead of use. A hint: a no-op for compilers without
//! the builtin.
template <class Object>
void prefetch(const Object& object) {
#if defined(__GNUC__)
  const char* bytes = reinterpret_cast<const char*>(&object);
  for (std::size_t b = 0; b < sizeof(Object); b += 64) __builtin_prefetch(bytes + b);
  __builtin_prefetch(bytes + sizeof(Object) - 1);
#else
  (void)object;
#endif
}

//! Visits the particles with indices [first, last) in chunks: prefetch(p) for the particles
//! of the next chunk, then prepare(p, slot) for every particle of this chunk, then
//! finish(p, slot). The set-up of a particle (loads; weights: floor, int conversions,
//! polynomials; a division) is a latency chain; done for a chunk at once it is independent
//! work the CPU overlaps instead of a stall at the head of every particle's stencil loop.
//! The prefetch one chunk ahead keeps the particle streams (several channels, and runs
//! broken where particles changed buckets) ahead of the loads.
constexpr std::ptrdiff_t chunk_size = 16;
template <class Prefetch, class Prepare, class Finish>
[[gnu::always_inline]] inline void in_chunks(const std::uint32_t* first, const std::uint32_t* last, Prefetch&& prefetch,
                                             Prepare&& prepare, Finish&& finish) {
  const std::ptrdiff_t n = last - first;
  for (std::ptrdiff_t i = 0; i < std::min(n, chunk_size); ++i) prefetch(first[i]);
  for (std::ptrdiff_t i = 0; i < n; i += chunk_size) {
    const std::ptrdiff_t end = std::min(n, i + chunk_size);
    for (std::ptrdiff_t j = end; j < std::min(n, end + chunk_size); ++j) prefetch(first[j]);
    for (std::ptrdiff_t j = i; j < end; ++j) prepare(first[j], static_cast<int>(j - i));
    for (std::ptrdiff_t j = i; j < end; ++j) finish(first[j], static_cast<int>(j - i));
  }
}

//! n values of T in one GCC/Clang vector: the compiler maps it onto the widest registers
//! the function's target has (4 doubles: two SSE registers in the baseline code, one AVX
//! register in the AVX2 code of with_simd). Eigen's fixed-size types pick their packets
//! when the library is compiled, so they stay on SSE even in a function compiled for AVX2.
template <class T, int n>
struct PackOf;
template <>
struct PackOf<double, 2> {
  typedef double type __attribute__((vector_size(16)));
};
template <>
struct PackOf<double, 4> {
  typedef double type __attribute__((vector_size(32)));
};
template <>
struct PackOf<float, 2> {
  typedef float type __attribute__((vector_size(8)));
};
template <>
struct PackOf<float, 4> {
  typedef float type __attribute__((vector_size(16)));
};
template <class T, int n>
using Pack = typename PackOf<T, n>::type;

//! By reference: a 32-byte vector passed by value has a different ABI with and without AVX.
template <class P, class T>
[[gnu::always_inline]] inline void load_pack(P& p, const T* values) {
  std::memcpy(&p, values, sizeof p);
}

#if defined(__GNUC__) && defined(__x86_64__)
template <class Fn, class... Args>
[[gnu::target("avx2")]] void call_avx2(const Fn& fn, Args... args) {
  fn(args...);
}
inline bool cpu_has_avx2() { return __builtin_cpu_supports("avx2"); }
#else
inline bool cpu_has_avx2() { return false; }
#endif

//! fn(args...) in AVX2 code when `avx2` (cpu_has_avx2(), asked once per transfer), else in
//! the baseline code. fn must be always_inline, down to its hot loops, so that its body is
//! compiled into each caller for that caller's target. Without FMA: the AVX2 code does the
//! operations of the baseline code in the same order, so results are bit for bit the same.
template <class Fn, class... Args>
[[gnu::always_inline]] inline void with_simd(bool avx2, const Fn& fn, Args... args) {
#if defined(__GNUC__) && defined(__x86_64__)
  if (avx2) return call_avx2(fn, args...);
#else
  (void)avx2;
#endif
  fn(args...);
}

//! The terms of the stress scatter along the row (j, k) of axis 0 (k unused in 2D): with
//! A = -S / dx and the gradient factored per axis, grad w = (dw_0 w_1 w_2, w_0 dw_1 w_2,
//! w_0 w_1 dw_2), the node i of the row takes w_0[i] P + dw_0[i] Q with P = A_1 dw_1 w_2 +
//! A_2 w_1 dw_2 and Q = A_0 w_1 w_2 (A_a the columns of A): two multiply-adds per node and
//! component where the per-node gradient and matrix product take a dozen.
template <int dim, int S, class T>
[[gnu::always_inline]] inline void gradient_row(const Stencil<dim, S, T>& st, const Eigen::Matrix<T, dim, dim>& A,
                                                int j, int k, Eigen::Matrix<T, dim, 1>& P,
                                                Eigen::Matrix<T, dim, 1>& Q) {
  if constexpr (dim == 2) {
    (void)k;
    P = st.dw[1][j] * A.col(1);
    Q = st.w[1][j] * A.col(0);
  } else {
    P = (st.dw[1][j] * st.w[2][k]) * A.col(1) + (st.w[1][j] * st.dw[2][k]) * A.col(2);
    Q = (st.w[1][j] * st.w[2][k]) * A.col(0);
  }
}

//! Adds w (c[0] + sum_a rel_a c[a+1]) for every stencil node into the first channels of the
//! patch (Ch values per node; 0: as many as Node has); the rel terms only when `affine`. With
//! the integer node offsets n_a = rel_a - rel_a[0] the value is c0 + sum_a n_a c[a+1],
//! c0 = c[0] + sum_a rel_a[0] c[a+1]: along a row it grows by c[1] from node to node, so a node
//! costs one multiply-add. With `A` (= -S / dx; the stencil computed with dw) the same node
//! visit also adds A grad w_i [1/cell] into the dim channels after Node's (gradient_row), or,
//! with `gradient_in_momentum`, into Node's channels 1 .. dim (A = -dt S / dx: an impulse).
template <bool affine, int stride = 0, bool gradient_in_momentum = false, int dim, int S, class T, class Node>
[[gnu::always_inline]] inline void spread(const Stencil<dim, S, T>& st, const Node (&c)[dim + 1], T* patch,
                                          const Eigen::Matrix<T, dim, dim>* A = nullptr) {
  using VecT = Eigen::Matrix<T, dim, 1>;
  constexpr int N = Node::RowsAtCompileTime;
  constexpr int Ch = stride ? stride : N;
  constexpr bool gradient = gradient_in_momentum || Ch >= N + dim;
  constexpr int gradient_channel = gradient_in_momentum ? 1 : N;
  static_assert(Ch >= N);
  constexpr int W = patch_width<dim>;
  Node c0 = c[0];
  if constexpr (affine)
    for (int a = 0; a < dim; ++a) c0.noalias() += st.rel[a][0] * c[a + 1];
  // q: the value at the row's first node; P, Q: the stress terms of the row (gradient)
  const auto row = [&](int offset, T w_outer, const Node& q, [[maybe_unused]] int j, [[maybe_unused]] int k) {
    Node v = w_outer * q;
    const Node step = w_outer * c[1];
    [[maybe_unused]] VecT P, Q;
    if constexpr (gradient) gradient_row(st, *A, j, k, P, Q);
    for (int i = 0; i < S; ++i) {
      T* node = patch + (offset + i) * Ch;
      Eigen::Map<Node>(node).noalias() += st.w[0][i] * v;
      if constexpr (affine) v += step;
      if constexpr (gradient) {
        const VecT f = st.w[0][i] * P + st.dw[0][i] * Q;
        for (int a = 0; a < dim; ++a) node[gradient_channel + a] += f[a];
      }
    }
  };
  if constexpr (dim == 2) {
    Node q = c0;
    for (int j = 0; j < S; ++j) {
      row(st.patch_offset + W * j, st.w[1][j], q, j, 0);
      if constexpr (affine) q += c[2];
    }
  } else {
    Node qk = c0;
    for (int k = 0; k < S; ++k) {
      Node q = qk;
      for (int j = 0; j < S; ++j) {
        row(st.patch_offset + W * (j + W * k), st.w[1][j] * st.w[2][k], q, j, k);
        if constexpr (affine) q += c[2];
      }
      if constexpr (affine) qk += c[3];
    }
  }
}

//! Adds A grad w_i [1/cell] to the Ch-channel patch entries at channel `first` (dim values) of
//! every stencil node: the stress scatter f_i -= S grad w_i with A = -S / dx (gradient_row).
template <int Ch, int dim, int S, class T>
[[gnu::always_inline]] inline void spread_gradient(const Stencil<dim, S, T>& st, const Eigen::Matrix<T, dim, dim>& A,
                                                   T* patch, int first) {
  using VecT = Eigen::Matrix<T, dim, 1>;
  constexpr int W = patch_width<dim>;
  const auto row = [&](int offset, int j, int k) {
    VecT P, Q;
    gradient_row(st, A, j, k, P, Q);
    for (int i = 0; i < S; ++i) {
      const VecT f = st.w[0][i] * P + st.dw[0][i] * Q;
      for (int a = 0; a < dim; ++a) patch[(offset + i) * Ch + first + a] += f[a];
    }
  };
  for (int k = 0; k < (dim == 3 ? S : 1); ++k)
    for (int j = 0; j < S; ++j) row(st.patch_offset + W * (j + W * k), j, k);
}

//! acc = x for the first term of a sum, acc += x after: starting from zero is not free
//! (-0 + 0 = +0 keeps the compiler from dropping the add).
template <class Acc, class X>
[[gnu::always_inline]] inline void accumulate(bool first, Acc& acc, const X& x) {
  if (first)
    acc = x;
  else
    acc += x;
}

//! Moments of the node values v (Ch values apart in the patch; Lanes = Pack<T, Ch>) over the
//! stencil: s = sum w v and t[a] = sum w n_a v with the integer node offsets
//! n_a = rel_a - rel_a[0], so sum w rel_a v = t[a] + rel_a[0] s. Integer offsets turn the
//! moments into sums of the products w v: a node costs one multiply and a few adds. With
//! `gradient` (the stencil computed with dw) also g[a] = sum (dw/dxi_a) v [1/cell], the velocity
//! gradient's column a, from the same loads: the row sums of w v and dw v share each node.
template <int Ch, bool gradient = false, int dim, int S, class T, class Lanes>
[[gnu::always_inline]] inline void collect(const Stencil<dim, S, T>& st, const T* patch, Lanes& s, Lanes (&t)[dim],
                                           [[maybe_unused]] Lanes* g = nullptr) {
  constexpr int W = patch_width<dim>;
  // Along axis 0: sum w v, sum n_0 w v and (gradient) sum dw v.
  const auto row = [&](int offset, Lanes& m0, Lanes& m1, [[maybe_unused]] Lanes& md) {
    for (int i = 0; i < S; ++i) {
      Lanes v;
      load_pack(v, patch + (offset + i) * Ch);
      const Lanes wv = st.w[0][i] * v;
      accumulate(i == 0, m0, wv);
      if (i > 0) accumulate(i == 1, m1, T(i) * wv);
      if constexpr (gradient) accumulate(i == 0, md, st.dw[0][i] * v);
    }
  };
  Lanes m0, m1, md{};
  if constexpr (dim == 2) {
    for (int j = 0; j < S; ++j) {
      row(st.patch_offset + W * j, m0, m1, md);
      const Lanes b = st.w[1][j] * m0;
      accumulate(j == 0, s, b);
      accumulate(j == 0, t[0], st.w[1][j] * m1);
      if (j > 0) accumulate(j == 1, t[1], T(j) * b);
      if constexpr (gradient) {
        accumulate(j == 0, g[0], st.w[1][j] * md);
        accumulate(j == 0, g[1], st.dw[1][j] * m0);
      }
    }
  } else {
    for (int k = 0; k < S; ++k) {
      Lanes M0, M1, M2;               // over the rows of one k: sum w v, sum n_0 w v, sum n_1 w v
      [[maybe_unused]] Lanes G0, G1;  // (gradient) over the rows of one k: sum dw_0 w_1 v, sum w_0 dw_1 v
      for (int j = 0; j < S; ++j) {
        row(st.patch_offset + W * (j + W * k), m0, m1, md);
        const Lanes b = st.w[1][j] * m0;
        accumulate(j == 0, M0, b);
        accumulate(j == 0, M1, st.w[1][j] * m1);
        if (j > 0) accumulate(j == 1, M2, T(j) * b);
        if constexpr (gradient) {
          accumulate(j == 0, G0, st.w[1][j] * md);
          accumulate(j == 0, G1, st.dw[1][j] * m0);
        }
      }
      const Lanes d = st.w[2][k] * M0;
      accumulate(k == 0, s, d);
      accumulate(k == 0, t[0], st.w[2][k] * M1);
      accumulate(k == 0, t[1], st.w[2][k] * M2);
      if (k > 0) accumulate(k == 1, t[2], T(k) * d);
      if constexpr (gradient) {
        accumulate(k == 0, g[0], st.w[2][k] * G0);
        accumulate(k == 0, g[1], st.w[2][k] * G1);
        accumulate(k == 0, g[2], st.dw[2][k] * M0);
      }
    }
  }
}

//! p2g's scatter: the stress term A = scale S_p grad w_ip into the force channels (scale =
//! -1 / dx) or, with `impulse`, into the momentum (scale = -dt / dx).
template <int dim, class K, bool affine, bool impulse, class PS, class T, std::size_t Ch>
void p2g_scatter(const PS& P, const ParticleBuckets<dim>& buckets, const K& kernel, const SparseGrid<dim>& grid,
                 const std::array<BasicChannelView<T>, Ch>& channels,
                 [[maybe_unused]] const Eigen::Matrix<T, dim, dim>* weighted_stress, [[maybe_unused]] T scale,
                 [[maybe_unused]] const T* stress_weight) {
  constexpr bool stress = impulse || Ch == 2 * dim + 1;
  using Node = Eigen::Matrix<T, dim + 1, 1>;
  using MatT = Eigen::Matrix<T, dim, dim>;
  const T dx = static_cast<T>(grid.dx());
  scatter_buckets<dim, int(Ch), K::support>(
      grid, buckets, channels,
      [&](const std::uint32_t* first, const std::uint32_t* last, const PatchFrame<dim>& f, T* patch) {
        Stencil<dim, K::support, T> st[chunk_size];
        Node c[chunk_size][dim + 1];
        [[maybe_unused]] MatT A[stress ? chunk_size : 1];  // scale S_p
        in_chunks(
            first, last,
            [&](std::uint32_t p) {
              prefetch(P.x[p]);
              prefetch(P.v[p]);
              prefetch(P.C[p]);
              prefetch(P.mass[p]);
              if constexpr (stress) {
                prefetch(weighted_stress[p]);
                if (stress_weight) prefetch(stress_weight[p]);
              }
            },
            [&](std::uint32_t p, int q) {
              st[q].template compute<stress>(kernel, f.cells(P.x[p]), f.origin);
              const T m = P.mass[p];
              c[q][0] << m, m * P.v[p];
              for (int a = 0; a < dim; ++a) c[q][a + 1] << T(0), (m * dx) * P.C[p].col(a);
              if constexpr (stress) {
                if (stress_weight)
                  A[q] = scale * (stress_weight[p] * weighted_stress[p]);
                else
                  A[q] = scale * weighted_stress[p];
              }
            },
            [&](std::uint32_t, int q) {
              spread<affine, int(Ch), impulse>(st[q], c[q], patch, stress ? &A[q] : nullptr);
            });
      });
}

//! Adds (w m_p, w m_p (v_p + C_p (x_i - x_p))) into channels {mass, momentum_0..dim-1}
//! (C_p term only when `affine`). With 2 dim + 1 channels, the next dim channels also take the
//! stress forces -S_p grad w_ip of `weighted_stress` (indexed like the particles; times
//! `stress_weight`[p] where given: ParticleStress) in the same pass: the sums of each channel
//! are those of a separate scatter, bit for bit. With `impulse_dt` > 0 (and dim + 1 channels)
//! the momentum takes the impulse -dt S_p grad w_ip instead: the grid update's
//! v = (p + dt f) / m without a force channel.
template <int dim, class K, bool affine, class PS, class T, std::size_t Ch>
void p2g(const PS& P, const ParticleBuckets<dim>& buckets, const K& kernel, const SparseGrid<dim>& grid,
         const std::array<BasicChannelView<T>, Ch>& channels,
         [[maybe_unused]] const Eigen::Matrix<T, dim, dim>* weighted_stress = nullptr, T impulse_dt = 0,
         const T* stress_weight = nullptr) {
  constexpr bool force_channels = Ch == 2 * dim + 1;
  static_assert(force_channels || Ch == dim + 1);
  if constexpr (!force_channels)
    if (weighted_stress) {
      MPM_VERIFY(impulse_dt > 0, Error, "p2g: stresses without force channels need a time step");
      p2g_scatter<dim, K, affine, true>(P, buckets, kernel, grid, channels, weighted_stress, -impulse_dt / T(grid.dx()),
                                        stress_weight);
      return;
    }
  p2g_scatter<dim, K, affine, false>(P, buckets, kernel, grid, channels, weighted_stress, -1 / T(grid.dx()),
                                     stress_weight);
}

//! APIC (flip = false): v_p = sum w v_i, C_p = B_p D_p^-1 from `velocity` channels.
//! FLIP (flip = true): v_p = a (v_p + sum w (v_i - v_i^old)) + (1 - a) v^PIC from `velocity`
//! followed by `velocity_old` channels (2 dim of them). Both advect x_p += dt v^PIC.
//! With `deform`, the same gather also updates F_p = (I + dt grad v_p) F_p in `F` (indexed like
//! the particles), grad v_p = sum_i v_i (grad w_ip)^T at x_p before the advection: the
//! deformation update without a second pass over particles and grid. `then`, when given, is
//! called with each bucket's particles after their gather (Then: a ParticleGroupUpdate).
template <int dim, class K, bool flip, bool deform = false, class PS, class T, std::size_t Ch, class Then = void>
void g2p(PS& P, const ParticleBuckets<dim>& buckets, const K& kernel, const SparseGrid<dim>& grid,
         const std::array<BasicChannelView<T>, Ch>& channels, T flip_ratio, T dt,
         Eigen::Matrix<T, dim, dim>* F = nullptr, const Then* then = nullptr) {
  static_assert(Ch == (flip ? 2 * dim : dim));
  using VecT = Eigen::Matrix<T, dim, 1>;
  using MatT = Eigen::Matrix<T, dim, dim>;
  // APIC reads the velocity padded to a whole number of SIMD packets (the extra lane repeats
  // component 0 and is ignored), so the stencil sums are packet operations.
  constexpr int lanes = flip || dim != 3 ? int(Ch) : 4;
  std::array<BasicChannelView<T>, lanes> read;
  for (int c = 0; c < lanes; ++c) read[c] = channels[c < int(Ch) ? c : 0];
  const T inv_dx = static_cast<T>(1.0 / grid.dx());
  // F_p <- (I + dt grad v) F_p with grad v = G inv_dx, G's columns g[a] [1/cell].
  [[maybe_unused]] const auto deform_particle = [&](std::uint32_t p, const MatT& G) __attribute__((always_inline)) {
    F[p] = (MatT::Identity() + (dt * inv_dx) * G) * F[p];
  };
  const auto bucket = [&](const std::uint32_t* first, const std::uint32_t* last, const PatchFrame<dim>* f,
                          const T* patch) __attribute__((always_inline)) {
    Stencil<dim, K::support, T> st[chunk_size];
    T inv_D[chunk_size][dim];  // APIC D_p^-1 [1/cells^2]; its division overlaps in the set-up
    in_chunks(
        first, last,
        [&](std::uint32_t p) __attribute__((always_inline)) {
          prefetch(P.x[p]);
          prefetch(P.v[p]);
          if constexpr (!flip) prefetch(P.C[p]);
          if constexpr (deform) prefetch(F[p]);
        },
        [&](std::uint32_t p, int q) __attribute__((always_inline)) {
          st[q].template compute<flip || deform>(kernel, f->cells(P.x[p]), f->origin);
          if constexpr (!flip) st[q].inverse_inertia(inv_D[q]);
        },
        [&](std::uint32_t p, int q) __attribute__((always_inline)) {
          if constexpr (flip) {
            VecT v_pic = VecT::Zero();
            VecT dv = VecT::Zero();
            MatT G = MatT::Zero();
            st[q].for_each_node([&](int node, T w, const VecT& grad, const VecT&) {
              const Eigen::Map<const VecT> vi(patch + node * lanes);
              v_pic.noalias() += w * vi;
              dv.noalias() += w * (vi - Eigen::Map<const VecT>(patch + node * lanes + dim));
              if constexpr (deform) G.noalias() += vi * grad.transpose();
            });
            if constexpr (deform) deform_particle(p, G);
            P.v[p] = flip_ratio * (P.v[p] + dv) + (1 - flip_ratio) * v_pic;
            P.x[p] += dt * v_pic;
          } else {
            using Lanes = Pack<T, lanes>;
            Lanes s, t[dim];  // B_p = sum w v (x_i - x_p)^T [cells]: column a is t[a] + rel_a[0] s
            Lanes g[dim];     // (deform) column a of grad v [1/cell]
            collect<lanes, deform>(st[q], patch, s, t, g);
            for (int a = 0; a < dim; ++a) {
              const Lanes column = (t[a] + st[q].rel[a][0] * s) * (inv_D[q][a] * inv_dx);
              for (int b = 0; b < dim; ++b) P.C[p](b, a) = column[b];
            }
            if constexpr (deform) {
              MatT G;
              for (int a = 0; a < dim; ++a)
                for (int b = 0; b < dim; ++b) G(b, a) = g[a][b];
              deform_particle(p, G);
            }
            for (int b = 0; b < dim; ++b) {
              P.v[p][b] = s[b];
              P.x[p][b] += dt * s[b];
            }
          }
        });
    if constexpr (!std::is_void_v<Then>)
      if (then) (*then)(first, last);
  };
  const bool avx2 = cpu_has_avx2();
  gather_buckets<dim, lanes, K::support>(
      grid, buckets, read,
      [&](const std::uint32_t* first, const std::uint32_t* last, const PatchFrame<dim>& f, const T* patch) {
        with_simd(avx2, bucket, first, last, &f, patch);
      });
}

}  // namespace mpm::detail
