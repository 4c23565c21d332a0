#pragma once
//! The P2G and G2P loops of transfer.h (equations there) over any particle storage PS whose
//! channels x, v, C, mass hold scalar T: Particles<dim> (T = double) in the library, a
//! single-precision copy in bench/bench_transfer.cpp. Internal.
//!
//! The stencil is a tensor product, and the APIC node value is affine in the node offset,
//!   m_p (v_p + C_p (x_i - x_p)) = c_0 + sum_a rel_a c_{a+1},  c_0 = (m, m v), c_{a+1} = (0, m C e_a dx),
//! so both loops factor it one axis at a time, outermost first: P2G folds an axis's weight
//! and offset into the coefficients c (spread), G2P sums the moments sum w v and
//! sum w rel_a v one axis at a time (collect). The innermost loop over the S nodes of a row
//! is then two multiply-adds of a node's channels instead of a weight product and a
//! matrix-vector product per node.
#include <mpm/core/detail/bucket_loops.h>

namespace mpm::detail {

//! Adds w (c[0] + sum_a rel_a c[a+1]) for every stencil node into the patch (Ch values per
//! node); the rel terms only when `affine`.
template <bool affine, int dim, int S, class T, class Node>
[[gnu::always_inline]] inline void spread(const Stencil<dim, S, T>& st, const Node (&c)[dim + 1], T* patch) {
  constexpr int Ch = Node::RowsAtCompileTime;
  constexpr int W = patch_width<dim>;
  const auto row = [&](int offset, const Node& q, const Node& e) {  // nodes along axis 0
    for (int i = 0; i < S; ++i) {
      Eigen::Map<Node> out(patch + (offset + i) * Ch);
      if constexpr (affine) out += st.w[0][i] * q + (st.w[0][i] * st.rel[0][i]) * e;
      else out += st.w[0][i] * q;
    }
  };
  if constexpr (dim == 2) {
    for (int j = 0; j < S; ++j)
      row(st.patch_offset + W * j, st.w[1][j] * (c[0] + st.rel[1][j] * c[2]), st.w[1][j] * c[1]);
  } else {
    for (int k = 0; k < S; ++k) {
      const T wk = st.w[2][k];
      const Node qk = wk * (c[0] + st.rel[2][k] * c[3]), bk = wk * c[2], ek = wk * c[1];
      for (int j = 0; j < S; ++j)
        row(st.patch_offset + W * (j + W * k), st.w[1][j] * (qk + st.rel[1][j] * bk), st.w[1][j] * ek);
    }
  }
}

//! Moments of the node values v (Ch values apart in the patch) over the stencil:
//! s = sum w v and t[a] = sum w rel_a v.
template <int Ch, int dim, int S, class T, class VecT>
[[gnu::always_inline]] inline void collect(const Stencil<dim, S, T>& st, const T* patch, VecT& s, VecT (&t)[dim]) {
  constexpr int W = patch_width<dim>;
  const auto row = [&](int offset, VecT& rs, VecT& rt) {  // nodes along axis 0
    rs.setZero();
    rt.setZero();
    for (int i = 0; i < S; ++i) {
      const Eigen::Map<const VecT> v(patch + (offset + i) * Ch);
      rs.noalias() += st.w[0][i] * v;
      rt.noalias() += (st.w[0][i] * st.rel[0][i]) * v;
    }
  };
  s.setZero();
  for (VecT& ta : t) ta.setZero();
  VecT rs, rt;
  if constexpr (dim == 2) {
    for (int j = 0; j < S; ++j) {
      row(st.patch_offset + W * j, rs, rt);
      s.noalias() += st.w[1][j] * rs;
      t[0].noalias() += st.w[1][j] * rt;
      t[1].noalias() += (st.w[1][j] * st.rel[1][j]) * rs;
    }
  } else {
    for (int k = 0; k < S; ++k) {
      VecT sk = VecT::Zero(), t0k = VecT::Zero(), t1k = VecT::Zero();
      for (int j = 0; j < S; ++j) {
        row(st.patch_offset + W * (j + W * k), rs, rt);
        sk.noalias() += st.w[1][j] * rs;
        t0k.noalias() += st.w[1][j] * rt;
        t1k.noalias() += (st.w[1][j] * st.rel[1][j]) * rs;
      }
      const T wk = st.w[2][k];
      s.noalias() += wk * sk;
      t[0].noalias() += wk * t0k;
      t[1].noalias() += wk * t1k;
      t[2].noalias() += (wk * st.rel[2][k]) * sk;
    }
  }
}

//! Adds (w m_p, w m_p (v_p + C_p (x_i - x_p))) into channels {mass, momentum_0..dim-1}
//! (C_p term only when `affine`).
template <int dim, class K, bool affine, class PS, class T>
void p2g(const PS& P, const ParticleBuckets<dim>& buckets, const K& kernel,
         const SparseGrid<dim>& grid, const std::array<BasicChannelView<T>, dim + 1>& channels) {
  using Node = Eigen::Matrix<T, dim + 1, 1>;
  const T dx = static_cast<T>(grid.dx());
  scatter<dim, dim + 1>(grid, buckets, channels, [&](std::uint32_t p, const PatchFrame<dim>& f, T* patch) {
    Stencil<dim, K::support, T> st;
    st.compute(kernel, f.cells(P.x[p]), f.origin);
    const T m = P.mass[p];
    Node c[dim + 1];
    c[0] << m, m * P.v[p];
    for (int a = 0; a < dim; ++a) c[a + 1] << T(0), (m * dx) * P.C[p].col(a);
    spread<affine>(st, c, patch);
  });
}

//! APIC (flip = false): v_p = sum w v_i, C_p = B_p D_p^-1 from `velocity` channels.
//! FLIP (flip = true): v_p = a (v_p + sum w (v_i - v_i^old)) + (1 - a) v^PIC from `velocity`
//! followed by `velocity_old` channels (2 dim of them). Both advect x_p += dt v^PIC.
template <int dim, class K, bool flip, class PS, class T, std::size_t Ch>
void g2p(PS& P, const ParticleBuckets<dim>& buckets, const K& kernel, const SparseGrid<dim>& grid,
         const std::array<BasicChannelView<T>, Ch>& channels, T flip_ratio, T dt) {
  static_assert(Ch == (flip ? 2 * dim : dim));
  using VecT = Eigen::Matrix<T, dim, 1>;
  const T inv_dx = static_cast<T>(1.0 / grid.dx());
  gather<dim, int(Ch)>(grid, buckets, channels, [&](std::uint32_t p, const PatchFrame<dim>& f, const T* patch) {
    Stencil<dim, K::support, T> st;
    st.compute(kernel, f.cells(P.x[p]), f.origin);
    VecT v_pic;
    if constexpr (flip) {
      v_pic.setZero();
      VecT dv = VecT::Zero();
      st.for_each_node([&](int node, T w, const VecT&, const VecT&) {
        const Eigen::Map<const VecT> vi(patch + node * Ch);
        v_pic.noalias() += w * vi;
        dv.noalias() += w * (vi - Eigen::Map<const VecT>(patch + node * Ch + dim));
      });
      P.v[p] = flip_ratio * (P.v[p] + dv) + (1 - flip_ratio) * v_pic;
    } else {
      VecT t[dim];  // column a of B_p = sum w v (x_i - x_p)^T, in cells
      collect<int(Ch)>(st, patch, v_pic, t);
      const VecT inv_D = st.inverse_inertia() * inv_dx;
      for (int a = 0; a < dim; ++a) P.C[p].col(a) = t[a] * inv_D[a];
      P.v[p] = v_pic;
    }
    P.x[p] += dt * v_pic;
  });
}

}  // namespace mpm::detail
