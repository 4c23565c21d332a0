// The explicit solid step on a CUDA device (one launch per phase, particles resident):
//   stable_dt  max |v_p|^2 over the particles (one reduction, read back for dt)
//   sort       block key of each particle's first stencil node; a radix sort of (key, index)
//              pairs gives the particles of each block in a run, without moving particle data
//   blocks     the 2^3 blocks each particle block's stencils reach are marked in a table of the
//              domain's blocks (4 B per 4^3 nodes) and numbered by a scan: node storage is
//              allocated for the marked blocks only (a sparse block grid)
//   p2g        one thread block per particle block scatters m, m (v + C (x_i - x_p)) and the
//              stress impulse -dt V^0 tau grad w (Gao et al. 2017 eq. 1-2; APIC, Jiang et al.
//              2015) into a shared-memory tile of 6^3 nodes, then adds the tile to the grid
//   grid       v_i = p_i / m_i + dt g, then the colliders and the walls (collider.h)
//   g2p        one thread block per particle block gathers the tile of its node velocities into
//              shared memory; each particle forms v, C, grad v, F <- (I + dt grad v) F,
//              x += dt v, the return map and the Kirchhoff stress of the next step in one pass
// The equations are those of the CPU stages (p2g, stress_forces, grid_update, boundary, g2p,
// plasticity); device_math.cuh holds the per-particle algebra.
#include "device_math.cuh"

#include <mpm/core/error.h>

#include <cub/cub.cuh>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <string>
#include <type_traits>

namespace mpm::cuda::detail {

namespace {

void check(cudaError_t e, const char* what) {
  if (e != cudaSuccess) throw Error(std::string("CUDA: ") + what + ": " + cudaGetErrorString(e));
}

//! Device memory of n elements of T, grown on demand (contents lost when it grows).
template <class T>
class Buffer {
public:
  Buffer() = default;
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  ~Buffer() { cudaFree(data_); }
  void reserve(std::size_t n) {
    if (n <= capacity_) return;
    cudaFree(data_);
    data_ = nullptr;
    capacity_ = 0;
    check(cudaMalloc(&data_, n * sizeof(T)), "allocating device memory");
    capacity_ = n;
  }
  T* get() const { return data_; }
  std::size_t bytes() const { return capacity_ * sizeof(T); }
  void swap(Buffer& other) {
    std::swap(data_, other.data_);
    std::swap(capacity_, other.capacity_);
  }

private:
  T* data_ = nullptr;
  std::size_t capacity_ = 0;
};

constexpr int kBlockBits = 2;  // 4 nodes per axis, as SparseGrid<3>
constexpr int kBlockNodes = 64;
constexpr int kTile = 6;  // a block's nodes and the two beyond it per axis
constexpr int kTileNodes = kTile * kTile * kTile;
constexpr unsigned kNone = 0xffffffffu;
// Threads per particle block: P2G 128, G2P 256, the faster of 128 and 256 for each on an H100
// (docs/performance.md, "The CUDA step").
constexpr int kP2gThreads = 128;
constexpr int kG2pThreads = 256;

enum ErrorBit : unsigned { kOutside = 1, kGridNotFinite = 2, kParticleNotFinite = 4 };

//! Particle channels on the device, component-major.
template <class T>
struct ParticleView {
  T *x, *v, *C, *F, *tau, *plastic, *mass, *volume0;
  std::uint16_t* material;
  std::size_t n;
};

struct GridFrame {
  double origin[3];
  double dx, inv_dx;
  int node_counts[3];
  int blocks[3];  //!< blocks per axis of the domain's block table
};

__device__ __forceinline__ unsigned block_key(const GridFrame& g, int bx, int by, int bz) {
  return (static_cast<unsigned>(bz) * g.blocks[1] + by) * g.blocks[0] + bx;
}

// Rounded arithmetic without contraction into FMAs: the binning (keys_kernel) and both
// transfers must find the same first stencil node for a particle, bit for bit.
__device__ __forceinline__ float add_rn(float a, float b) { return __fadd_rn(a, b); }
__device__ __forceinline__ double add_rn(double a, double b) { return __dadd_rn(a, b); }
__device__ __forceinline__ float mul_rn(float a, float b) { return __fmul_rn(a, b); }
__device__ __forceinline__ double mul_rn(double a, double b) { return __dmul_rn(a, b); }

//! A particle coordinate in cells, xi = (x - origin) / dx, and its first stencil node.
template <class T>
__device__ __forceinline__ T cells(T x, double origin, double inv_dx) {
  return mul_rn(add_rn(x, T(-origin)), T(inv_dx));
}
template <class T>
__device__ __forceinline__ int first_node(T xi) {
  return static_cast<int>(floor(add_rn(xi, T(-0.5))));
}

//! Quadratic B-spline weights of one axis (kernels.h, QuadraticBSpline): base node, w, dw/dxi,
//! and f = xi - base.
template <class T>
__device__ __forceinline__ int quadratic(T xi, T (&w)[3], T (&dw)[3], T& f) {
  const int base = first_node(xi);
  f = xi - T(base);
  const T a = T(1.5) - f, b = f - T(1), c = f - T(0.5);
  w[0] = T(0.5) * a * a;
  w[1] = T(0.75) - b * b;
  w[2] = T(0.5) * c * c;
  dw[0] = -a;
  dw[1] = T(-2) * b;
  dw[2] = c;
  return base;
}

template <class T>
__global__ void max_speed_kernel(ParticleView<T> P, unsigned long long* result) {
  double m = 0.0;
  for (std::size_t p = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; p < P.n;
       p += std::size_t(gridDim.x) * blockDim.x) {
    const T a = P.v[p], b = P.v[P.n + p], c = P.v[2 * P.n + p];
    const double s = double(a * a + b * b + c * c);
    m = s > m || s != s ? s : m;  // a NaN wins, so that the host sees it
  }
  for (int offset = 16; offset > 0; offset /= 2) {
    const double o = __shfl_down_sync(0xffffffffu, m, offset);
    m = o > m || o != o ? o : m;
  }
  if ((threadIdx.x & 31) == 0) atomicMax(result, static_cast<unsigned long long>(__double_as_longlong(m)));
}

//! The sort key of each particle: the block of its first stencil node, and with `cell` also that
//! node's place in the block (6 low bits), so that a move of the data leaves the particles of a
//! cell side by side: the warp-reduced P2G then finds its peers in neighbouring lanes.
template <class T, bool cell>
__global__ void keys_kernel(ParticleView<T> P, GridFrame g, unsigned* keys, unsigned* index, unsigned* errors) {
  const std::size_t p = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (p >= P.n) return;
  int b[3], local[3];
  bool inside = true;
#pragma unroll
  for (int a = 0; a < 3; ++a) {
    // Tested before the conversion to int, which would turn NaN into 0 and saturate huge values:
    // the first stencil node must lie in [0, node_counts - 3].
    const T first = add_rn(cells(P.x[a * P.n + p], g.origin[a], g.inv_dx), T(-0.5));
    int base = 0;
    if (first >= T(0) && first < T(g.node_counts[a] - 2))
      base = static_cast<int>(floor(first));  // first_node(), from the same rounded value
    else
      inside = false;  // NaN positions too
    b[a] = base >> kBlockBits;
    local[a] = base & ((1 << kBlockBits) - 1);
  }
  if (!inside) atomicOr(errors, kOutside);
  const unsigned key = block_key(g, b[0], b[1], b[2]);
  keys[p] =
      cell ? key << (3 * kBlockBits) | unsigned((local[2] << kBlockBits | local[1]) << kBlockBits | local[0]) : key;
  index[p] = static_cast<unsigned>(p);
}

__device__ __forceinline__ void decode(const GridFrame& g, unsigned key, int (&b)[3]) {
  b[0] = key % g.blocks[0];
  key /= g.blocks[0];
  b[1] = key % g.blocks[1];
  b[2] = key / g.blocks[1];
}

//! Marks the blocks that the stencils of a particle block reach: the block and its +1 neighbours.
__global__ void mark_kernel(GridFrame g, const unsigned* segment_keys, const int* segments, unsigned* flags) {
  const int s = blockIdx.x * blockDim.x + threadIdx.x;
  if (s >= *segments) return;
  int b[3];
  decode(g, segment_keys[s], b);
  for (int c = 0; c < 8; ++c) {
    const int x = b[0] + (c & 1), y = b[1] + ((c >> 1) & 1), z = b[2] + (c >> 2);
    if (x < g.blocks[0] && y < g.blocks[1] && z < g.blocks[2]) flags[block_key(g, x, y, z)] = 1;
  }
}

//! slot[k] = storage index of block k or kNone; active[slot] = k; count = number of blocks.
__global__ void compact_kernel(std::size_t table, const unsigned* flags, unsigned* slot, unsigned* active, int* count) {
  const std::size_t k = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (k >= table) return;
  if (flags[k]) {
    active[slot[k]] = static_cast<unsigned>(k);
    if (k == table - 1) *count = static_cast<int>(slot[k] + 1);
  } else {
    if (k == table - 1) *count = static_cast<int>(slot[k]);
    slot[k] = kNone;
  }
}

//! Storage index of a node (its block allocated).
__device__ __forceinline__ std::size_t node_index(const GridFrame& g, const unsigned* slot, int i, int j, int k) {
  const unsigned s = slot[block_key(g, i >> kBlockBits, j >> kBlockBits, k >> kBlockBits)];
  return std::size_t(s) * kBlockNodes + ((k & 3) << 4 | (j & 3) << 2 | (i & 3));
}

template <class T>
struct GridView {
  T* mass;
  T* momentum;  //!< 3 channels of `nodes`; velocity after the grid update
  std::size_t nodes;
};

//! a[i] for a run-time i in 0..2 without indexing a register array (which would go to local memory).
template <class T>
__device__ __forceinline__ T pick(const T (&a)[3], int i) {
  return i == 0 ? a[0] : (i == 1 ? a[1] : a[2]);
}

//! One particle's P2G terms (Gao et al. 2017 eq. 1-2, APIC): its stencil in the tile of its
//! block and what it adds to each of the 27 nodes. An empty share (no particle) adds zeros.
template <class T, bool stress>
struct P2gShare {
  T w[3][3], dw[3][3], f[3];
  int local[3];  //!< first stencil node in the tile
  T m, mv[3], mC[3][3], A[3][3];

  __device__ void load(const ParticleView<T>& P, const GridFrame& g, const int (&o)[3], unsigned p, T dt) {
    const T dx = T(g.dx), inv_dx = T(g.inv_dx);
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      local[a] = quadratic(cells(P.x[a * P.n + p], g.origin[a], g.inv_dx), w[a], dw[a], f[a]) - o[a];
    }
    m = P.mass[p];
    // Node value: m v + (m dx C) rel + A (dw_0 w_1 w_2, w_0 dw_1 w_2, w_0 w_1 dw_2), rel = node - x_p
    // [cells], A = -dt V0 tau / dx (the stress impulse, stress_forces.cpp).
    const T* tau = P.tau;
    T s[3][3] = {};
    if constexpr (stress) {
      const T e[6] = {tau[p], tau[P.n + p], tau[2 * P.n + p], tau[3 * P.n + p], tau[4 * P.n + p], tau[5 * P.n + p]};
      s[0][0] = e[0], s[1][1] = e[1], s[2][2] = e[2];
      s[0][1] = s[1][0] = e[3], s[0][2] = s[2][0] = e[4], s[1][2] = s[2][1] = e[5];
    }
#pragma unroll
    for (int r = 0; r < 3; ++r) {
      mv[r] = m * P.v[r * P.n + p];
#pragma unroll
      for (int c = 0; c < 3; ++c) {
        mC[r][c] = m * dx * P.C[(3 * r + c) * P.n + p];
        A[r][c] = stress ? -dt * inv_dx * s[r][c] : T(0);
      }
    }
  }

  __device__ void clear() {
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      local[a] = 0, f[a] = T(0);
#pragma unroll
      for (int k = 0; k < 3; ++k) w[a][k] = dw[a][k] = T(0);
    }
    m = T(0);
#pragma unroll
    for (int r = 0; r < 3; ++r) {
      mv[r] = T(0);
#pragma unroll
      for (int c = 0; c < 3; ++c) mC[r][c] = A[r][c] = T(0);
    }
  }

  //! The share of node (i, j, k) of the stencil: value = {mass, momentum (3)}; returns its tile index.
  __device__ int node(int i, int j, int k, T (&value)[4]) const {
    const T w0 = pick(w[0], i), w1 = pick(w[1], j), w2 = pick(w[2], k);
    const T d0 = pick(dw[0], i), d1 = pick(dw[1], j), d2 = pick(dw[2], k);
    const T wjk = w1 * w2;
    const T weight = w0 * wjk;
    const T rel[3] = {T(i) - f[0], T(j) - f[1], T(k) - f[2]};
    const T grad[3] = {d0 * wjk, w0 * d1 * w2, w0 * w1 * d2};
    value[0] = weight * m;
#pragma unroll
    for (int r = 0; r < 3; ++r) {
      value[1 + r] = weight * (mv[r] + mC[r][0] * rel[0] + mC[r][1] * rel[1] + mC[r][2] * rel[2]);
      if constexpr (stress) value[1 + r] += A[r][0] * grad[0] + A[r][1] * grad[1] + A[r][2] * grad[2];
    }
    return (local[2] + k) * kTile * kTile + (local[1] + j) * kTile + local[0] + i;
  }
};

//! The tile of a particle block: 4 channels (mass, momentum) of 6^3 nodes, cleared.
template <class T>
__device__ void clear_tile(T (&tile)[4][kTileNodes]) {
  for (int t = threadIdx.x; t < 4 * kTileNodes; t += blockDim.x) (&tile[0][0])[t] = T(0);
}

//! Adds the tile to the grid's nodes (one global atomic per channel of a touched node).
template <class T>
__device__ void flush_tile(const T (&tile)[4][kTileNodes], const GridFrame& g, const GridView<T>& G,
                           const unsigned* slot, const int (&o)[3]) {
  for (int t = threadIdx.x; t < kTileNodes; t += blockDim.x) {
    const T m = tile[0][t];
    if (m == T(0)) continue;
    const int i = o[0] + t % kTile, j = o[1] + (t / kTile) % kTile, k = o[2] + t / (kTile * kTile);
    const std::size_t n = node_index(g, slot, i, j, k);
    atomicAdd(&G.mass[n], m);
#pragma unroll
    for (int r = 0; r < 3; ++r) atomicAdd(&G.momentum[r * G.nodes + n], tile[1 + r][t]);
  }
}

//! P2G with one shared-memory atomic per node channel and particle (the scatter before the
//! warp reduction; the faster one in double precision: DeviceScene::p2g_scatter).
template <class T, bool stress>
__global__ void __launch_bounds__(kP2gThreads)
    p2g_atomic_kernel(ParticleView<T> P, GridFrame g, GridView<T> G, const unsigned* segment_keys,
                      const unsigned* offsets, const unsigned* counts, const unsigned* order, const unsigned* slot,
                      T dt) {
  __shared__ T tile[4][kTileNodes];
  clear_tile(tile);
  int b[3];
  decode(g, segment_keys[blockIdx.x], b);
  const int o[3] = {b[0] << kBlockBits, b[1] << kBlockBits, b[2] << kBlockBits};
  __syncthreads();
  const unsigned first = offsets[blockIdx.x], count = counts[blockIdx.x];
  for (unsigned q = threadIdx.x; q < count; q += blockDim.x) {
    P2gShare<T, stress> share;
    share.load(P, g, o, order[first + q], dt);
    // Each lane starts its 27 nodes at another node, so that lanes whose particles share a cell
    // add to different tile entries at the same time: same-address shared atomics serialise.
    const int start = threadIdx.x % 27;
    for (int m27 = 0; m27 < 27; ++m27) {
      const int n27 = m27 + start < 27 ? m27 + start : m27 + start - 27;
      T value[4];
      const int t = share.node(n27 % 3, (n27 / 3) % 3, n27 / 9, value);
#pragma unroll
      for (int c = 0; c < 4; ++c) atomicAdd(&tile[c][t], value[c]);
    }
  }
  __syncthreads();
  flush_tile(tile, g, G, slot, o);
}

//! P2G with a warp-level reduction (Gao et al. 2018, sec. 4.2, for particles grouped by cell):
//! the lanes of a warp whose particles share a first stencil node ("peers", found by
//! __match_any_sync, in any lane order) add their shares of each node in a tree of shuffles,
//! and only the group's first lane adds the sum to the tile. Same-address shared atomics,
//! which serialise (compare-and-swap loops), drop from one per particle to one per cell.
template <class T, bool stress>
__global__ void __launch_bounds__(kP2gThreads)
    p2g_warp_kernel(ParticleView<T> P, GridFrame g, GridView<T> G, const unsigned* segment_keys,
                    const unsigned* offsets, const unsigned* counts, const unsigned* order, const unsigned* slot,
                    T dt) {
  __shared__ T tile[4][kTileNodes];
  clear_tile(tile);
  int b[3];
  decode(g, segment_keys[blockIdx.x], b);
  const int o[3] = {b[0] << kBlockBits, b[1] << kBlockBits, b[2] << kBlockBits};
  __syncthreads();
  const unsigned first = offsets[blockIdx.x], count = counts[blockIdx.x];
  const unsigned lane = threadIdx.x & 31u, warp_first = threadIdx.x - lane;
  constexpr unsigned kAll = 0xffffffffu;
  for (unsigned q0 = 0; q0 < count; q0 += blockDim.x) {  // uniform in the block: whole warps shuffle
    if (q0 + warp_first >= count) break;
    const unsigned q = q0 + threadIdx.x;
    const bool has = q < count;
    P2gShare<T, stress> share;
    if (has)
      share.load(P, g, o, order[first + q], dt);
    else
      share.clear();
    // Peers: same first stencil node (its cell in the block, 0..63); an empty lane is alone.
    const unsigned key = has ? unsigned((share.local[2] * 4 + share.local[1]) * 4 + share.local[0]) : 64u + lane;
    const unsigned peers = __match_any_sync(kAll, key);
    const unsigned rank = __popc(peers & ((1u << lane) - 1u)), size = __popc(peers);
    unsigned largest = size;  // the largest group of the warp: the rounds of the tree
#pragma unroll
    for (int offset = 16; offset > 0; offset /= 2) largest = max(largest, __shfl_xor_sync(kAll, largest, offset));
    // Tree over the ranks: in round r, rank k (k mod 2^(r+1) = 0) adds rank k + 2^r's partial
    // sum. The rounds' sources are found once per particle, for all 27 nodes (compile-time
    // indices: the arrays stay in registers).
    unsigned source[5];
    bool adds[5];
#pragma unroll
    for (int r = 0; r < 5; ++r) {
      const unsigned d = 1u << r;
      unsigned above = peers & ~((2u << lane) - 1u);                  // the peers after this lane
      for (unsigned s = 1; s < d && above; ++s) above &= above - 1u;  // less the first d - 1
      adds[r] = (rank & (2u * d - 1u)) == 0u && rank + d < size;
      source[r] = adds[r] ? unsigned(__ffs(above) - 1) : lane;
    }
#pragma unroll
    for (int n27 = 0; n27 < 27; ++n27) {
      T value[4];
      const int t = share.node(n27 % 3, (n27 / 3) % 3, n27 / 9, value);
#pragma unroll
      for (int r = 0; r < 5; ++r) {
        if ((1u << r) >= largest) break;  // uniform in the warp
#pragma unroll
        for (int c = 0; c < 4; ++c) {
          const T other = __shfl_sync(kAll, value[c], source[r]);
          if (adds[r]) value[c] += other;
        }
      }
      if (has && rank == 0u) {
#pragma unroll
        for (int c = 0; c < 4; ++c) atomicAdd(&tile[c][t], value[c]);
      }
    }
  }
  __syncthreads();
  flush_tile(tile, g, G, slot, o);
}

template <class T>
__device__ void apply_contact(int type, double friction, T (&v)[3], const T (&n)[3]) {
  if (type == 0) {
    v[0] = v[1] = v[2] = T(0);
    return;
  }
  const T vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
  if (type == 1) {
#pragma unroll
    for (int a = 0; a < 3; ++a) v[a] -= vn * n[a];
    return;
  }
  if (vn >= T(0)) return;
  T vt[3];
#pragma unroll
  for (int a = 0; a < 3; ++a) vt[a] = v[a] - vn * n[a];
  const T vt_norm = sqrt(vt[0] * vt[0] + vt[1] * vt[1] + vt[2] * vt[2]);
  if (vt_norm <= -T(friction) * vn) {
    v[0] = v[1] = v[2] = T(0);
    return;
  }
  const T scale = T(1) + T(friction) * vn / vt_norm;
#pragma unroll
  for (int a = 0; a < 3; ++a) v[a] = vt[a] * scale;
}

//! Collider::project for the analytic shapes.
template <class T>
__device__ void project(const DeviceCollider& c, const T (&x)[3], double t, T (&v)[3]) {
  if (t > c.until) return;
  T y[3], n[3] = {T(0), T(0), T(0)}, phi;
#pragma unroll
  for (int a = 0; a < 3; ++a) y[a] = c.translating ? x[a] - T(t * c.velocity[a]) : x[a];
  if (c.shape == DeviceCollider::half_space) {
    phi = T(0);
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      phi += (y[a] - T(c.a[a])) * T(c.b[a]);
      n[a] = T(c.b[a]);
    }
  } else if (c.shape == DeviceCollider::sphere) {
    T d[3];
#pragma unroll
    for (int a = 0; a < 3; ++a) d[a] = y[a] - T(c.a[a]);
    const T r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    phi = r - T(c.b[0]);
    if (r > T(0)) {
#pragma unroll
      for (int a = 0; a < 3; ++a) n[a] = d[a] / r;
    } else {
      n[0] = T(1);
    }
  } else {  // box (signed_distance.h, box_distance)
    T q[3], outside[3];
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      q[a] = fabs(y[a] - T(c.a[a])) - T(c.b[a]);
      outside[a] = fmax(q[a], T(0));
    }
    const T od = sqrt(outside[0] * outside[0] + outside[1] * outside[1] + outside[2] * outside[2]);
    T gradient[3] = {T(0), T(0), T(0)};
    if (od > T(0)) {
      phi = od;
#pragma unroll
      for (int a = 0; a < 3; ++a) gradient[a] = outside[a] / od;
    } else {
      int face = 0;
      for (int a = 1; a < 3; ++a)
        if (q[a] > q[face]) face = a;
      phi = q[face];
      gradient[face] = T(1);
    }
#pragma unroll
    for (int a = 0; a < 3; ++a) n[a] = (y[a] - T(c.a[a]) < T(0) ? T(-1) : T(1)) * gradient[a];
  }
  if (c.hollow) {
    phi = -phi;
#pragma unroll
    for (int a = 0; a < 3; ++a) n[a] = -n[a];
  }
  if (phi > T(0)) return;
  T rel[3];
#pragma unroll
  for (int a = 0; a < 3; ++a) rel[a] = v[a] - T(c.velocity[a]);
  apply_contact(c.contact, c.friction, rel, n);
#pragma unroll
  for (int a = 0; a < 3; ++a) v[a] = T(c.velocity[a]) + rel[a];
}

struct BoundaryView {
  const DeviceCollider* colliders;
  int count;
  DeviceWalls walls;
};

template <class T>
__global__ void grid_kernel(GridFrame g, GridView<T> G, const unsigned* active, std::size_t nodes, T dt, double t_end,
                            double3 gravity, BoundaryView boundary, unsigned* errors) {
  const std::size_t n = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (n >= nodes) return;
  const T m = G.mass[n];
  T v[3] = {T(0), T(0), T(0)};
  if (!(m <= T(0))) {  // a NaN mass too: the check below must see it, as grid_update does
    const T gv[3] = {T(gravity.x), T(gravity.y), T(gravity.z)};
#pragma unroll
    for (int a = 0; a < 3; ++a) v[a] = G.momentum[a * G.nodes + n] / m + dt * gv[a];
    // Checked before the obstacles, which could set a non-finite velocity to a finite one.
    if (!(isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]))) atomicOr(errors, kGridNotFinite);
    int b[3];
    decode(g, active[n / kBlockNodes], b);
    const int local = static_cast<int>(n % kBlockNodes);
    const int node[3] = {(b[0] << kBlockBits) | (local & 3), (b[1] << kBlockBits) | ((local >> 2) & 3),
                         (b[2] << kBlockBits) | (local >> 4)};
    // The obstacles act in double precision in both precisions: whether a node lies inside one
    // must not depend on T's rounding (a node on the inner face of a wall's layer, say).
    double x[3], u[3];
#pragma unroll
    for (int a = 0; a < 3; ++a) x[a] = g.origin[a] + node[a] * g.dx, u[a] = double(v[a]);
    for (int c = 0; c < boundary.count; ++c) project(boundary.colliders[c], x, t_end, u);
    const DeviceWalls& w = boundary.walls;
    if (w.present)
      for (int a = 0; a < 3; ++a) {
        double e[3] = {0.0, 0.0, 0.0};
        e[a] = 1.0;
        if (w.contact[2 * a] >= 0 && x[a] - w.lo[a] <= w.layer)
          apply_contact(w.contact[2 * a], w.friction[2 * a], u, e);
        e[a] = -1.0;
        if (w.contact[2 * a + 1] >= 0 && w.hi[a] - x[a] <= w.layer)
          apply_contact(w.contact[2 * a + 1], w.friction[2 * a + 1], u, e);
      }
#pragma unroll
    for (int a = 0; a < 3; ++a) v[a] = T(u[a]);
  }
#pragma unroll
  for (int a = 0; a < 3; ++a) G.momentum[a * G.nodes + n] = v[a];
}

template <class T, bool deform>
__global__ void __launch_bounds__(kG2pThreads)
    g2p_kernel(ParticleView<T> P, GridFrame g, GridView<T> G, const unsigned* segment_keys, const unsigned* offsets,
               const unsigned* counts, const unsigned* order, const unsigned* slot, const DeviceMaterial* materials,
               T dt, unsigned* errors) {
  __shared__ T tile[3][kTileNodes];
  int b[3];
  decode(g, segment_keys[blockIdx.x], b);
  const int o[3] = {b[0] << kBlockBits, b[1] << kBlockBits, b[2] << kBlockBits};
  for (int t = threadIdx.x; t < kTileNodes; t += blockDim.x) {
    const int i = o[0] + t % kTile, j = o[1] + (t / kTile) % kTile, k = o[2] + t / (kTile * kTile);
    const bool inside = i < g.node_counts[0] && j < g.node_counts[1] && k < g.node_counts[2];
    const std::size_t n = inside ? node_index(g, slot, i, j, k) : 0;
#pragma unroll
    for (int r = 0; r < 3; ++r) tile[r][t] = inside ? G.momentum[r * G.nodes + n] : T(0);
  }
  __syncthreads();
  const T inv_dx = T(g.inv_dx);
  const unsigned first = offsets[blockIdx.x], count = counts[blockIdx.x];
  for (unsigned q = threadIdx.x; q < count; q += blockDim.x) {
    const unsigned p = order[first + q];
    T w[3][3], dw[3][3], f[3];
    int local[3];
    T xp[3];
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      xp[a] = P.x[a * P.n + p];
      local[a] = quadratic(cells(xp[a], g.origin[a], g.inv_dx), w[a], dw[a], f[a]) - o[a];
    }
    T v[3] = {T(0), T(0), T(0)}, B[3][3] = {}, G3[3][3] = {};
#pragma unroll
    for (int k = 0; k < 3; ++k)
#pragma unroll
      for (int j = 0; j < 3; ++j)
#pragma unroll
        for (int i = 0; i < 3; ++i) {
          const T wjk = w[1][j] * w[2][k];
          const T weight = w[0][i] * wjk;
          const T rel[3] = {T(i) - f[0], T(j) - f[1], T(k) - f[2]};
          const T grad[3] = {dw[0][i] * wjk, w[0][i] * dw[1][j] * w[2][k], w[0][i] * w[1][j] * dw[2][k]};
          const int t = (local[2] + k) * kTile * kTile + (local[1] + j) * kTile + local[0] + i;
#pragma unroll
          for (int r = 0; r < 3; ++r) {
            const T vi = tile[r][t];
            v[r] += weight * vi;
#pragma unroll
            for (int c = 0; c < 3; ++c) {
              B[r][c] += weight * vi * rel[c];
              if constexpr (deform) G3[r][c] += vi * grad[c];
            }
          }
        }
    // APIC C = B D^-1 with D the stencil's inertia per axis (sum_k w_k rel_k^2 [cells^2]).
    T inv_D[3];
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      T D = T(0);
#pragma unroll
      for (int k = 0; k < 3; ++k) D += w[a][k] * (T(k) - f[a]) * (T(k) - f[a]);
      inv_D[a] = T(1) / D;
    }
#pragma unroll
    for (int r = 0; r < 3; ++r)
#pragma unroll
      for (int c = 0; c < 3; ++c) P.C[(3 * r + c) * P.n + p] = B[r][c] * inv_D[c] * inv_dx;
#pragma unroll
    for (int a = 0; a < 3; ++a) {
      P.v[a * P.n + p] = v[a];
      P.x[a * P.n + p] = xp[a] + dt * v[a];
    }
    if constexpr (deform) {  // F, the return map and the next step's stress
      M3<T> F, L;
#pragma unroll
      for (int r = 0; r < 3; ++r)
#pragma unroll
        for (int c = 0; c < 3; ++c) {
          F(r, c) = P.F[(3 * r + c) * P.n + p];
          L(r, c) = (r == c ? T(1) : T(0)) + dt * inv_dx * G3[r][c];
        }
      F = multiply(L, F);
      const DeviceMaterial& material = materials[P.material[p]];
      T plastic = P.plastic[p];
      Svd3<T> svd;
      return_map(material, F, plastic, svd);
      T tau[6];
      kirchhoff(material, svd, tau);
      const T V0 = P.volume0[p];
      bool finite = true;
#pragma unroll
      for (int e = 0; e < 9; ++e) {
        const T value = F.m[e / 3][e % 3];
        finite = finite && isfinite(value);
        P.F[e * P.n + p] = value;
      }
#pragma unroll
      for (int e = 0; e < 6; ++e) P.tau[e * P.n + p] = V0 * tau[e];
      P.plastic[p] = plastic;
      if (!finite) atomicOr(errors, kParticleNotFinite);
    }
  }
}

//! V0 tau of the uploaded F (the first step's stress; later steps take it from g2p).
template <class T>
__global__ void stress_kernel(ParticleView<T> P, const DeviceMaterial* materials) {
  const std::size_t p = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (p >= P.n) return;
  M3<T> F;
#pragma unroll
  for (int e = 0; e < 9; ++e) F.m[e / 3][e % 3] = P.F[e * P.n + p];
  const Svd3<T> f = svd3(F);
  T tau[6];
  kirchhoff(materials[P.material[p]], f, tau);
#pragma unroll
  for (int e = 0; e < 6; ++e) P.tau[e * P.n + p] = P.volume0[p] * tau[e];
}

//! Counts the places where the sorted order breaks a run of consecutive particles: few breaks,
//! long runs, coalesced particle loads in the transfers.
__global__ void breaks_kernel(const unsigned* order, std::size_t n, unsigned* breaks) {
  const std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  const bool broken = i + 1 < n && order[i + 1] != order[i] + 1;
  const unsigned votes = __ballot_sync(0xffffffffu, broken);
  if ((threadIdx.x & 31) == 0 && votes) atomicAdd(breaks, static_cast<unsigned>(__popc(votes)));
}

//! Moves the particle data into the sorted order: to[c][i] = from[c][order[i]], channel c =
//! blockIdx.y (the last y: material and host index). Blocks run in the order of their index, x
//! first, so the random reads of one channel (n values, tens of MB) hit the L2 cache.
template <class T>
__global__ void permute_kernel(const T* from, T* to, int channels, const std::uint16_t* material_from,
                               std::uint16_t* material_to, const unsigned* host_from, unsigned* host_to,
                               const unsigned* order, std::size_t n) {
  const std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (i >= n) return;
  const std::size_t p = order[i];
  const int c = blockIdx.y;
  if (c < channels) {
    to[c * n + i] = from[c * n + p];
  } else {
    material_to[i] = material_from[p];
    host_to[i] = host_from[p];
  }
}

//! One channel of the particles into the host's order and precision: to[host[p]] = from[p], so
//! that the download copies contiguous memory and the host does no scatter.
template <class T>
__global__ void to_host_order_kernel(const T* from, double* to, const unsigned* host, std::size_t n) {
  const std::size_t p = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (p < n) to[host[p]] = double(from[p]);
}

__global__ void iota_kernel(unsigned* out, std::size_t n) {
  const std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x;
  if (i < n) out[i] = static_cast<unsigned>(i);
}

unsigned blocks_for(std::size_t n, int threads = 256) { return static_cast<unsigned>((n + threads - 1) / threads); }

int bits_for(std::size_t values) {
  int bits = 1;
  while ((std::size_t(1) << bits) < values) ++bits;
  return bits;
}

class Events {
public:
  Events() {
    for (auto& e : events_) check(cudaEventCreate(&e), "creating an event");
  }
  ~Events() {
    for (auto& e : events_) cudaEventDestroy(e);
  }
  cudaEvent_t operator[](int i) const { return events_[i]; }
  double seconds(int a, int b) const {
    float ms = 0.0f;
    check(cudaEventElapsedTime(&ms, events_[a], events_[b]), "reading an event");
    return 1e-3 * ms;
  }

private:
  cudaEvent_t events_[5];
};

template <class T>
class Solid final : public DeviceSolid {
public:
  explicit Solid(const DeviceScene& scene)
      : scene_(scene),
        warp_reduced_(scene.p2g_scatter == DeviceScene::Scatter::warp_reduced ||
                      (scene.p2g_scatter == DeviceScene::Scatter::automatic && std::is_same_v<T, float>)) {
    for (int a = 0; a < 3; ++a) {
      frame_.origin[a] = scene.origin[a];
      frame_.node_counts[a] = scene.node_counts[a];
      frame_.blocks[a] = (scene.node_counts[a] + 3) >> kBlockBits;
    }
    frame_.dx = scene.dx;
    frame_.inv_dx = 1.0 / scene.dx;
    table_ = std::size_t(frame_.blocks[0]) * frame_.blocks[1] * frame_.blocks[2];
    if (table_ >= kNone)
      throw InputError("device: cuda: the grid has " + std::to_string(table_) + " blocks, more than 2^32");
    flags_.reserve(table_);
    slot_.reserve(table_);
    active_.reserve(table_);
    materials_.reserve(std::max<std::size_t>(scene.materials.size(), 1));
    check(cudaMemcpy(materials_.get(), scene.materials.data(), scene.materials.size() * sizeof(DeviceMaterial),
                     cudaMemcpyHostToDevice),
          "copying the materials");
    colliders_.reserve(std::max<std::size_t>(scene.colliders.size(), 1));
    if (!scene.colliders.empty())
      check(cudaMemcpy(colliders_.get(), scene.colliders.data(), scene.colliders.size() * sizeof(DeviceCollider),
                       cudaMemcpyHostToDevice),
            "copying the colliders");
    scalars_.reserve(8);
    check(cudaMallocHost(&host_scalars_, 8 * sizeof(unsigned long long)), "allocating pinned memory");
  }
  ~Solid() override { cudaFreeHost(host_scalars_); }

  void upload(const HostParticles& h) override {
    n_ = h.n;
    particles_.reserve(channels * n_);
    spare_.reserve(channels * n_);
    material_.reserve(n_);
    spare_material_.reserve(n_);
    host_index_.reserve(n_);
    spare_host_index_.reserve(n_);
    keys_.reserve(2 * n_);
    index_.reserve(2 * n_);
    segment_keys_.reserve(n_);
    counts_.reserve(n_);
    offsets_.reserve(n_);
    const auto put = [&](const std::vector<double>& values, std::size_t at) {
      std::vector<T> converted(values.begin(), values.end());
      check(cudaMemcpy(particles_.get() + at * n_, converted.data(), converted.size() * sizeof(T),
                       cudaMemcpyHostToDevice),
            "copying particles to the device");
    };
    put(h.x, kX);
    put(h.v, kV);
    put(h.C, kC);
    put(h.F, kF);
    put(h.plastic, kPlastic);
    put(h.mass, kMass);
    put(h.volume0, kVolume0);
    check(cudaMemcpy(material_.get(), h.material.data(), n_ * sizeof(std::uint16_t), cudaMemcpyHostToDevice),
          "copying particles to the device");
    if (n_ > 0) {
      iota_kernel<<<blocks_for(n_), 256>>>(host_index_.get(), n_);
      stress_kernel<<<blocks_for(n_), 256>>>(view(), materials_.get());
    }
    check(cudaGetLastError(), "stress kernel");
    temp_bytes_ = 0;  // sized again for n
  }

  void download(HostParticles& h) override {
    h.n = n_;
    // The device keeps the particles in its own order: host_index_ maps them back. Each component
    // goes into the host's order and precision on the device, in the spare buffer (the target of
    // a reordering only, not in use between steps: 33 n values of T >= n doubles), and is copied
    // as one block: the host's scatter of ten million particles took seconds per frame.
    double* scratch = reinterpret_cast<double*>(spare_.get());
    const auto get = [&](std::vector<double>& values, std::size_t at, int components) {
      values.resize(components * n_);
      for (int c = 0; c < components && n_ > 0; ++c) {
        to_host_order_kernel<<<blocks_for(n_), 256>>>(particles_.get() + (at + c) * n_, scratch, host_index_.get(), n_);
        check(cudaGetLastError(), "copying particles from the device");
        check(cudaMemcpy(values.data() + c * n_, scratch, n_ * sizeof(double), cudaMemcpyDeviceToHost),
              "copying particles from the device");
      }
    };
    get(h.x, kX, 3);
    get(h.v, kV, 3);
    get(h.C, kC, 9);
    get(h.F, kF, 9);
    get(h.plastic, kPlastic, 1);
  }

  double stable_dt() override {
    double dt = scene_.max_dt;
    if (scene_.wave_speed > 0.0) dt = std::min(dt, scene_.wave_cfl * scene_.dx / scene_.wave_speed);
    if (n_ == 0) return dt;
    check(cudaMemsetAsync(scalars_.get(), 0, sizeof(unsigned long long)), "max speed");
    max_speed_kernel<<<std::min(blocks_for(n_), 1024u), 256>>>(view(), scalars_.get());
    check(cudaMemcpy(host_scalars_, scalars_.get(), sizeof(unsigned long long), cudaMemcpyDeviceToHost), "max speed");
    double speed2 = 0.0;
    std::memcpy(&speed2, host_scalars_, sizeof speed2);
    if (!(speed2 < 1e300)) throw NumericalError("device step: a particle velocity is not finite");
    if (speed2 > 0.0) dt = std::min(dt, scene_.cfl * scene_.dx / std::sqrt(speed2));
    return dt;
  }

  void step(double dt, double t_end) override {
    timed_ = n_ > 0;
    if (n_ == 0) return;
    cudaEventRecord(events_[0]);
    unsigned* errors = reinterpret_cast<unsigned*>(scalars_.get() + 1);
    int* counts = reinterpret_cast<int*>(scalars_.get() + 2);  // [0] segments, [1] active blocks
    unsigned* breaks = reinterpret_cast<unsigned*>(scalars_.get() + 3);
    check(cudaMemsetAsync(scalars_.get() + 1, 0, 3 * sizeof(unsigned long long)), "step");
    // sort: (block key, index) pairs
    unsigned* keys_in = keys_.get();
    unsigned* keys_out = keys_.get() + n_;
    unsigned* index_in = index_.get();
    unsigned* index_out = index_.get() + n_;
    keys_kernel<T, false><<<blocks_for(n_), 256>>>(view(), frame_, keys_in, index_in, errors);
    reserve_temp();
    std::size_t bytes = temp_bytes_;
    const int key_bits = bits_for(table_);
    check(cub::DeviceRadixSort::SortPairs(temp_.get(), bytes, keys_in, keys_out, index_in, index_out, n_, 0, key_bits),
          "sorting particles");
    bytes = temp_bytes_;
    check(cub::DeviceRunLengthEncode::Encode(temp_.get(), bytes, keys_out, segment_keys_.get(), counts_.get(), counts,
                                             n_),
          "finding particle blocks");
    // blocks: mark, number, compact
    check(cudaMemsetAsync(flags_.get(), 0, table_ * sizeof(unsigned)), "block table");
    mark_kernel<<<blocks_for(n_), 256>>>(frame_, segment_keys_.get(), counts, flags_.get());
    bytes = temp_bytes_;
    check(cub::DeviceScan::ExclusiveSum(temp_.get(), bytes, flags_.get(), slot_.get(), table_), "numbering blocks");
    compact_kernel<<<blocks_for(table_), 256>>>(table_, flags_.get(), slot_.get(), active_.get(), counts + 1);
    breaks_kernel<<<blocks_for(n_), 256>>>(index_out, n_, breaks);
    check(cudaMemcpy(host_scalars_, scalars_.get() + 1, 3 * sizeof(unsigned long long), cudaMemcpyDeviceToHost),
          "reading the block counts");
    // Runs shorter than 4 particles on average: the transfers' loads would use a fraction of
    // each 32-byte sector, so the particle data moves into the sorted order (then the order is
    // the identity). Longer runs (a seeding lattice's rows, particles drifting across blocks)
    // keep their place: a move costs more than a few steps of gathers (docs/gpu.md).
    reordered_ = reinterpret_cast<const unsigned*>(host_scalars_ + 2)[0] > n_ / 4;
    if (reordered_ && key_bits + 3 * kBlockBits <= 32) {
      // The move puts the particles in cell order within their blocks (the block runs found
      // above stay: the block is the key's high part). Later steps sort by block only, and the
      // stable radix sort keeps this order for the particles that stay in their block.
      keys_kernel<T, true><<<blocks_for(n_), 256>>>(view(), frame_, keys_in, index_in, errors);
      bytes = temp_bytes_;
      check(cub::DeviceRadixSort::SortPairs(temp_.get(), bytes, keys_in, keys_out, index_in, index_out, n_, 0,
                                            key_bits + 3 * kBlockBits),
            "sorting particles by cell");
    }
    if (reordered_) {
      permute_kernel<T><<<dim3(blocks_for(n_), static_cast<unsigned>(channels + 1)), 256>>>(
          particles_.get(), spare_.get(), static_cast<int>(channels), material_.get(), spare_material_.get(),
          host_index_.get(), spare_host_index_.get(), index_out, n_);
      particles_.swap(spare_);
      material_.swap(spare_material_);
      host_index_.swap(spare_host_index_);
      iota_kernel<<<blocks_for(n_), 256>>>(index_out, n_);
    }
    const unsigned sort_errors = reinterpret_cast<const unsigned*>(host_scalars_)[0];
    if (sort_errors & kOutside)
      throw NumericalError("device step: a particle left the grid (its stencil reaches beyond the domain's nodes)");
    const int segments = reinterpret_cast<const int*>(host_scalars_ + 1)[0];
    active_blocks_ = reinterpret_cast<const int*>(host_scalars_ + 1)[1];
    bytes = temp_bytes_;
    check(cub::DeviceScan::ExclusiveSum(temp_.get(), bytes, counts_.get(), offsets_.get(), segments), "offsets");
    nodes_ = std::size_t(active_blocks_) * kBlockNodes;
    grid_.reserve(4 * nodes_);
    check(cudaMemsetAsync(grid_.get(), 0, 4 * nodes_ * sizeof(T)), "clearing the grid");
    cudaEventRecord(events_[1]);
    const GridView<T> G{grid_.get(), grid_.get() + nodes_, nodes_};
    const auto p2g = warp_reduced_ ? (scene_.transfers_only ? p2g_warp_kernel<T, false> : p2g_warp_kernel<T, true>)
                                   : (scene_.transfers_only ? p2g_atomic_kernel<T, false> : p2g_atomic_kernel<T, true>);
    p2g<<<segments, kP2gThreads>>>(view(), frame_, G, segment_keys_.get(), offsets_.get(), counts_.get(), index_out,
                                   slot_.get(), T(dt));
    cudaEventRecord(events_[2]);
    const BoundaryView boundary{colliders_.get(), static_cast<int>(scene_.colliders.size()), scene_.walls};
    grid_kernel<T><<<blocks_for(nodes_), 256>>>(frame_, G, active_.get(), nodes_, T(dt), t_end,
                                                make_double3(scene_.gravity[0], scene_.gravity[1], scene_.gravity[2]),
                                                boundary, errors);
    cudaEventRecord(events_[3]);
    const auto g2p = scene_.transfers_only ? g2p_kernel<T, false> : g2p_kernel<T, true>;
    g2p<<<segments, kG2pThreads>>>(view(), frame_, G, segment_keys_.get(), offsets_.get(), counts_.get(), index_out,
                                   slot_.get(), materials_.get(), T(dt), errors);
    cudaEventRecord(events_[4]);
    check(cudaGetLastError(), "launching the step");
    check(cudaMemcpy(host_scalars_, scalars_.get() + 1, sizeof(unsigned long long), cudaMemcpyDeviceToHost),
          "the step");
    const unsigned step_errors = reinterpret_cast<const unsigned*>(host_scalars_)[0];
    if (step_errors & kGridNotFinite) throw NumericalError("device step: a grid node velocity is not finite");
    if (step_errors & kParticleNotFinite)
      throw NumericalError("device step: a particle's elastic deformation gradient F^E is not finite");
  }

  StepTimes last_times() const override {
    if (!timed_) return {};  // no particles, no step on the device
    return {events_.seconds(0, 1), events_.seconds(1, 2), events_.seconds(2, 3), events_.seconds(3, 4), reordered_};
  }

  std::size_t memory_bytes() const override {
    return particles_.bytes() + spare_.bytes() + material_.bytes() + spare_material_.bytes() + host_index_.bytes() +
           spare_host_index_.bytes() + keys_.bytes() + index_.bytes() + segment_keys_.bytes() + counts_.bytes() +
           offsets_.bytes() + flags_.bytes() + slot_.bytes() + active_.bytes() + grid_.bytes() + temp_.bytes();
  }

private:
  // Offsets of the particle channels, in units of n: x 3, v 3, C 9, F 9, tau 6, plastic, mass, volume0.
  static constexpr std::size_t kX = 0, kV = 3, kC = 6, kF = 15, kTau = 24, kPlastic = 30, kMass = 31, kVolume0 = 32,
                               channels = 33;

  ParticleView<T> view() const {
    T* base = particles_.get();
    return {base + kX * n_,       base + kV * n_,    base + kC * n_,       base + kF * n_,  base + kTau * n_,
            base + kPlastic * n_, base + kMass * n_, base + kVolume0 * n_, material_.get(), n_};
  }

  void reserve_temp() {
    if (temp_bytes_ > 0) return;
    std::size_t sort = 0, encode = 0, scan_table = 0, scan_particles = 0;
    unsigned* u = nullptr;
    int* count = nullptr;
    cub::DeviceRadixSort::SortPairs(nullptr, sort, u, u, u, u, n_, 0, std::min(bits_for(table_) + 3 * kBlockBits, 32));
    cub::DeviceRunLengthEncode::Encode(nullptr, encode, u, u, u, count, n_);
    cub::DeviceScan::ExclusiveSum(nullptr, scan_table, u, u, table_);
    cub::DeviceScan::ExclusiveSum(nullptr, scan_particles, u, u, n_);
    temp_bytes_ = std::max({sort, encode, scan_table, scan_particles, std::size_t(1)});
    temp_.reserve(temp_bytes_);
  }

  DeviceScene scene_;
  bool warp_reduced_;  //!< the P2G scatter (DeviceScene::p2g_scatter)
  GridFrame frame_{};
  std::size_t table_ = 0, n_ = 0, nodes_ = 0, temp_bytes_ = 0;
  int active_blocks_ = 0;
  Buffer<T> particles_, spare_, grid_;  // spare_: the target of a reordering, swapped in
  Buffer<std::uint16_t> material_, spare_material_;
  Buffer<unsigned> host_index_, spare_host_index_;  //!< the host's index of each device particle
  bool reordered_ = false;
  bool timed_ = false;  //!< the last step recorded its events
  Buffer<unsigned> keys_, index_, segment_keys_, counts_, offsets_, flags_, slot_, active_;
  Buffer<unsigned char> temp_;
  Buffer<unsigned long long> scalars_;
  Buffer<DeviceMaterial> materials_;
  Buffer<DeviceCollider> colliders_;
  unsigned long long* host_scalars_ = nullptr;
  Events events_;
};

}  // namespace

std::unique_ptr<DeviceSolid> make_device_solid(const DeviceScene& scene, bool single_precision) {
  if (const std::string why = device_unavailable_reason(); !why.empty()) throw Error("device: cuda: " + why);
  if (single_precision) return std::make_unique<Solid<float>>(scene);
  return std::make_unique<Solid<double>>(scene);
}

std::string device_unavailable_reason() {
  int count = 0;
  const cudaError_t e = cudaGetDeviceCount(&count);
  if (e != cudaSuccess) return std::string("no CUDA device is usable (") + cudaGetErrorString(e) + ")";
  if (count == 0) return "this machine has no CUDA device";
  return "";
}

std::string device_description() {
  if (!device_unavailable_reason().empty()) return "none";
  cudaDeviceProp prop{};
  int device = 0;
  cudaGetDevice(&device);
  cudaGetDeviceProperties(&prop, device);
  std::size_t free = 0, total = 0;
  cudaMemGetInfo(&free, &total);
  char text[256];
  std::snprintf(text, sizeof text, "%s (%.1f GiB free of %.1f GiB)", prop.name, free / 1073741824.0,
                total / 1073741824.0);
  return text;
}

std::size_t device_free_bytes() {
  if (!device_unavailable_reason().empty()) return 0;
  std::size_t free = 0, total = 0;
  cudaMemGetInfo(&free, &total);
  return free;
}

// 33 channels of T and the material index and host index, twice (the reordering's target), two
// (key, index) pairs, a segment key, count and offset (at most one per particle), and the sort's
// temporary storage (about 2 keys).
std::size_t bytes_per_particle(bool single_precision) {
  return 2 * (33 * (single_precision ? 4 : 8) + 2 + 4) + 4 * 4 + 3 * 4 + 16;
}
std::size_t bytes_per_block(bool single_precision) { return 4 * kBlockNodes * (single_precision ? 4 : 8); }
// flags, slot and active: 3 x 4 bytes per block of the domain, and the scan's storage.
std::size_t bytes_per_table_entry() { return 3 * 4 + 4; }

}  // namespace mpm::cuda::detail

namespace mpm::cuda {
bool built_with_cuda() { return true; }
}  // namespace mpm::cuda
