#include <mpm/adaptive/adaptive_transfer.h>

#include <mpm/core/detail/bucket_loops.h>
#include <mpm/core/error.h>

#include <tbb/parallel_for.h>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <map>

namespace mpm::adaptive {

namespace {
// fn(p, n, k, w, grad_w, x_k) over the stencil of every irregular particle (transfer level n):
// the groups of AdaptiveGrid::irregular_groups one colour after the other, the groups of a
// colour in parallel (the colouring keeps their stencils apart).
template <int dim, class Fn>
void scatter_irregular(const Particles<dim>& P, const AdaptiveGrid<dim>& grid, Fn&& fn) {
  const auto& groups = grid.irregular_groups();
  const bool serial = groups.begin.back() < detail::serial_below_particles;
  for (const std::vector<int>& same_color : groups.by_color)
    detail::for_each_range(same_color.size(), std::size_t{1}, serial, [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i)
        for (std::uint32_t e = groups.begin[same_color[i]]; e < groups.begin[same_color[i] + 1]; ++e) {
          const std::uint32_t p = grid.irregular()[e];
          const int n = grid.transfer_level(p);
          grid.for_each_weight(
              n, grid.half_cells(p), P.x[p],
              [&](Index k, double w, const Vec<dim>& grad, const Vec<dim>& xk) { fn(p, n, k, w, grad, xk); });
        }
    });
}

// The regular groups of level n with their kernels, for the uniform scatters.
template <int dim>
std::array<BucketGroup<dim>, AdaptiveGrid<dim>::groups_per_level> level_groups(const AdaptiveGrid<dim>& grid, int n) {
  std::array<BucketGroup<dim>, AdaptiveGrid<dim>::groups_per_level> groups;
  for (int i = 0; i < AdaptiveGrid<dim>::groups_per_level; ++i) {
    const int group = AdaptiveGrid<dim>::groups_per_level * n + i;
    groups[i] = {&grid.regular(group), grid.group_kernel(group)};
  }
  return groups;
}

// fn(p, n) for every irregular particle p (transfer level n), in parallel (G2P-like gathers);
// with `then`, each range of them goes through it right after its gathers.
template <int dim, class Fn>
void gather_irregular(const AdaptiveGrid<dim>& grid, Fn&& fn, const ParticleGroupUpdate* then) {
  const std::vector<std::uint32_t>& list = grid.irregular();
  detail::for_each_range(list.size(), std::size_t{256}, list.size() < detail::serial_below_particles,
                         [&](const tbb::blocked_range<std::size_t>& range) {
                           for (std::size_t i = range.begin(); i != range.end(); ++i)
                             fn(list[i], grid.transfer_level(list[i]));
                           if (then) (*then)(list.data() + range.begin(), list.data() + range.end());
                         });
}

// The particles near embedded ghosts (AdaptiveGrid::near_embedded), bucket by bucket: fn(b,
// kernel) for every bucket b of a regular group in parallel, with the group's kernel as its
// 3-node type. A scatter goes colour by colour (the patches of one colour's buckets share no
// node); a gather needs no colours.
enum class Walk { gather, scatter };
template <int dim, class Fn>
void for_each_near_bucket(const AdaptiveGrid<dim>& grid, int group, Walk walk, Fn&& fn) {
  const ParticleBuckets<dim>& near = grid.near_embedded(group);
  const bool serial = near.particle.size() < detail::serial_below_particles;
  std::visit(
      [&](const auto& kernel) {
        if constexpr (std::decay_t<decltype(kernel)>::support == 3) {
          if (walk == Walk::gather)
            detail::for_each_range(near.count(), 1, serial, [&](const auto& range) {
              for (int b = range.begin(); b != range.end(); ++b) fn(b, kernel);
            });
          else
            for (const std::vector<int>& same_color : near.by_color)
              detail::for_each_range(same_color.size(), std::size_t{1}, serial, [&](const auto& range) {
                for (std::size_t r = range.begin(); r != range.end(); ++r) fn(same_color[r], kernel);
              });
        } else {
          MPM_VERIFY(false, Error, "adaptive grid: the regular kernel has a 3-node stencil");
        }
      },
      grid.group_kernel(group));
}

// The nodes of a 3^dim stencil whose weight is not zero, by bit as in a mask (bit i_0 + 3 i_1
// + 9 i_2): a uGIMP box smaller than a cell leaves an outer node without weight on half of an
// axis's positions, so most embedded ghosts of the near particles' masks carry none.
template <int dim>
std::uint32_t weighted_nodes(const detail::Stencil<dim, 3>& st) {
  std::uint32_t nodes = 1;  // over the axes so far: 3^a bits
  for (int a = 0, width = 1; a < dim; ++a, width *= 3) {
    std::uint32_t wider = 0;
    for (int i = 0; i < 3; ++i)
      if (st.w[a][i] != 0.0) wider |= nodes << (width * i);
    nodes = wider;
  }
  return nodes;
}

// fn(patch index, w) for the embedded ghosts of a particle's regular stencil `st`: the nodes
// flagged in `mask` (AdaptiveGrid::near_embedded_masks, and'ed with weighted_nodes()), w their
// weight.
template <int dim, class Fn>
void for_each_embedded(const detail::Stencil<dim, 3>& st, std::uint32_t mask, Fn&& fn) {
  constexpr int W = detail::patch_width<dim>;
  for (; mask != 0; mask &= mask - 1) {
    const auto& digit = AdaptiveGrid<dim>::stencil_offsets[std::countr_zero(mask)];
    int node = st.patch_offset;
    double w = 1.0;
    for (int a = 0, stride = 1; a < dim; ++a, stride *= W) {
      node += digit[a] * stride;
      w *= st.w[a][digit[a]];
    }
    fn(node, w);
  }
}

// The nodes of a bucket's patch that the ghosts' terms visit, one by one: each node's storage
// index, and a bit per node so that each is set up once (a bucket's particles reach a few of
// its patch's nodes through their masks; the uniform loops' patch walk visits all of them).
template <int dim>
class VisitedNodes {
public:
  static constexpr int W = detail::patch_width<dim>, B = SparseGrid<dim>::block_size;

  VisitedNodes(const SparseGrid<dim>& g, BlockKey block) {
    const IVec<dim> origin = g.block_coord(block) * B;
    for (int corner = 0; corner < (1 << dim); ++corner) {
      IVec<dim> c = origin;
      for (int a = 0; a < dim; ++a) c[a] += ((corner >> a) & 1) * B;
      const int slot = g.slot(g.block_id(c));  // a bucket's patch blocks are all active (prepare)
      MPM_ASSERT(slot >= 0);
      first_[corner] = static_cast<std::size_t>(slot) * SparseGrid<dim>::nodes_per_block;
    }
  }
  //! True the first time `node` (a patch index) is passed.
  bool first_visit(int node) {
    std::uint64_t& word = seen_[static_cast<std::size_t>(node) / 64];
    const std::uint64_t bit = std::uint64_t{1} << (node % 64);
    const bool first = (word & bit) == 0;
    word |= bit;
    return first;
  }
  //! fn(patch index, storage index) for the nodes visited, in patch order.
  template <class Fn>
  void for_each_visited(Fn&& fn) const {
    for (std::size_t i = 0; i < seen_.size(); ++i)
      for (std::uint64_t word = seen_[i]; word != 0; word &= word - 1) {
        const int node = static_cast<int>(64 * i) + std::countr_zero(word);
        fn(node, storage_index(node));
      }
  }
  //! The storage index of patch node `node` (axis 0 fastest, W nodes per axis).
  std::size_t storage_index(int node) const {
    int corner = 0;
    IVec<dim> local;
    for (int a = 0; a < dim; ++a, node /= W) {
      const int i = node % W;
      corner |= (i >= B) << a;
      local[a] = i & (B - 1);
    }
    return first_[corner] + static_cast<std::size_t>(SparseGrid<dim>::local_index(local));
  }

private:
  std::array<std::size_t, 1 << dim> first_;  // storage index of each patch block's first node
  std::array<std::uint64_t, (detail::patch_nodes<dim> + 63) / 64> seen_{};
};

// APIC's G_k = sum_p w_kp m_p C_p of the embedded ghosts from the particles of a regular group
// near them, which the uniform loops gave their mass and momentum: per bucket into its patch,
// then onto the patch's ghosts (affine: the group's level's).
template <int dim>
void scatter_ghost_affine(const Particles<dim>& P, const AdaptiveGrid<dim>& grid, int group,
                          std::vector<Mat<dim>>& affine) {
  constexpr int M = dim * dim;
  const int n = AdaptiveGrid<dim>::group_level(group);
  const SparseGrid<dim>& g = grid.level(n);
  const auto& ghosts = grid.ghosts(n);
  const ParticleBuckets<dim>& near = grid.near_embedded(group);
  const std::vector<std::uint32_t>& masks = grid.near_embedded_masks(group);
  for_each_near_bucket(grid, group, Walk::scatter, [&](int b, const auto& kernel) {
    alignas(64) std::array<double, detail::patch_nodes<dim> * M> patch;  // set where visited
    VisitedNodes<dim> visited(g, near.block[b]);
    const detail::PatchFrame<dim> frame(g, near.block[b]);
    for (std::uint32_t e = near.begin[b]; e < near.begin[b + 1]; ++e) {
      const std::uint32_t p = near.particle[e];
      detail::Stencil<dim, 3> st;
      st.template compute<false>(kernel, frame.cells(P.x[p]), frame.origin);
      const std::uint32_t mask = masks[e] & weighted_nodes(st);
      if (mask == 0) continue;
      const Mat<dim> mC = P.mass[p] * P.C[p];
      for_each_embedded(st, mask, [&](int node, double w) {
        Eigen::Map<Mat<dim>> sum(patch.data() + node * M);
        if (visited.first_visit(node)) sum.setZero();
        sum += w * mC;
      });
    }
    visited.for_each_visited([&](int node, std::size_t k) {
      const int j = ghosts.of_node(k);
      MPM_ASSERT(j >= 0);  // the masks flag embedded ghosts
      affine[j] += Eigen::Map<const Mat<dim>>(patch.data() + node * M);
    });
  });
}

// What the uniform G2P leaves out for a regular particle whose stencil holds embedded ghosts:
// the ghosts' terms of B_p and D_p, dB = sum_ghost w_kp Q_k and dD = sum_ghost w_kp R_k, with
// D_p^u, the uniform loops' own (diagonal: the tensor weights reproduce linear fields). From
// the uniform C^u = B^u (D^u)^-1, C_p = (C^u D^u + dB) (D^u + dD)^-1. Ghosts that are real
// nodes of another level add nothing (their Q_k and R_k vanish): only the embedded ones are
// visited. Per bucket, each visited node's Q_k and R_k are read once; x_before: the
// particles' positions at P2G, in the order of near_embedded(group).particle.
template <int dim>
void add_ghost_terms(Particles<dim>& P, const AdaptiveGrid<dim>& grid, int group,
                     const std::vector<Vec<dim>>& x_before) {
  constexpr int M = dim * dim, Ch = 2 * M;  // Q_k, then R_k
  const int n = AdaptiveGrid<dim>::group_level(group);
  const SparseGrid<dim>& g = grid.level(n);
  const auto& ghosts = grid.ghosts(n);
  const ParticleBuckets<dim>& near = grid.near_embedded(group);
  const std::vector<std::uint32_t>& masks = grid.near_embedded_masks(group);
  const double dx = g.dx();
  for_each_near_bucket(grid, group, Walk::gather, [&](int b, const auto& kernel) {
    alignas(64) std::array<double, detail::patch_nodes<dim> * Ch> patch;  // read in where visited
    VisitedNodes<dim> visited(g, near.block[b]);
    const auto terms = [&](int node) -> const double* {
      double* out = patch.data() + node * Ch;
      if (!visited.first_visit(node)) return out;
      const int j = ghosts.of_node(visited.storage_index(node));
      MPM_ASSERT(j >= 0 && ghosts.moment[j] >= 0);  // the masks flag embedded ghosts
      std::copy_n(ghosts.velocity_moment[ghosts.moment[j]].data(), M, out);
      const Mat<dim> R = ghosts.spread_of(ghosts.moment[j]);
      std::copy_n(R.data(), M, out + M);
      return out;
    };
    const detail::PatchFrame<dim> frame(g, near.block[b]);
    for (std::uint32_t e = near.begin[b]; e < near.begin[b + 1]; ++e) {
      detail::Stencil<dim, 3> st;
      st.template compute<false>(kernel, frame.cells(x_before[e]), frame.origin);
      const std::uint32_t mask = masks[e] & weighted_nodes(st);
      if (mask == 0) continue;  // no ghost term: the uniform loops' C_p stands

      Vec<dim> D_uniform;  // [m^2]
      for (int a = 0; a < dim; ++a) {
        double D = 0;
        for (int k = 0; k < 3; ++k) D += st.w[a][k] * st.rel[a][k] * st.rel[a][k];
        D_uniform[a] = D * dx * dx;
      }
      Mat<dim> dB = Mat<dim>::Zero(), D = D_uniform.asDiagonal();
      for_each_embedded(st, mask, [&](int node, double w) {
        const double* QR = terms(node);
        dB.noalias() += w * Eigen::Map<const Mat<dim>>(QR);
        D.noalias() += w * Eigen::Map<const Mat<dim>>(QR + M);
      });
      const std::uint32_t p = near.particle[e];
      P.C[p] = (P.C[p] * D_uniform.asDiagonal() + dB) * D.inverse();
    }
  });
}

}  // namespace

template <int dim>
void particles_to_grid(const Particles<dim>& P, const TransferScheme& scheme, AdaptiveGrid<dim>& grid,
                       std::type_identity_t<ParticleStress<dim>> S, double impulse_dt) {
  MPM_ASSERT(grid.particle_count() == P.size());
  const bool apic = scheme.type == TransferScheme::Type::apic;
  const bool impulse = S && impulse_dt > 0.0;
  std::vector<std::vector<Mat<dim>>> affine(grid.levels());
  for (int n = 0; n < grid.levels(); ++n) {
    mpm::particles_to_grid<dim>(P, level_groups(grid, n), scheme, grid.level(n), S, impulse_dt);  // zeroes first
    affine[n].assign(grid.ghosts(n).node.size(), Mat<dim>::Zero());
  }
  scatter_irregular(P, grid, [&](std::size_t p, int n, Index k, double w, const Vec<dim>& grad, const Vec<dim>& xk) {
    SparseGrid<dim>& g = grid.level(n);
    if (impulse)
      g.velocity[k] -= impulse_dt * (S[p] * grad);
    else if (S)
      g.force[k] -= S[p] * grad;
    const double wm = w * P.mass[p];
    g.mass[k] += wm;
    if (apic) {
      g.velocity[k] += wm * (P.v[p] + P.C[p] * (xk - P.x[p]));
      if (const int j = grid.ghosts(n).of_node(k); j >= 0) affine[n][j] += wm * P.C[p];
    } else {
      g.velocity[k] += wm * P.v[p];
    }
  });
  for (int group = 0; apic && group < grid.regular_groups(); ++group)
    scatter_ghost_affine(P, grid, group, affine[AdaptiveGrid<dim>::group_level(group)]);
  grid.push_momentum(affine);
  if (S && !impulse) grid.push(grid.per_level(&SparseGrid<dim>::force));
}

template <int dim>
void momentum_to_velocity(AdaptiveGrid<dim>& grid, const TransferScheme& scheme) {
  for (int n = 0; n < grid.levels(); ++n) mpm::momentum_to_velocity(grid.level(n), scheme);
}

template <int dim>
void stress_to_grid_forces(const std::vector<Mat<dim>>& S, const Particles<dim>& P, AdaptiveGrid<dim>& grid) {
  MPM_ASSERT(grid.particle_count() == P.size());
  for (int n = 0; n < grid.levels(); ++n)  // zeroes first
    mpm::stress_to_grid_forces<dim>(S, P, level_groups(grid, n), grid.level(n));
  scatter_irregular(P, grid, [&](std::size_t p, int n, Index k, double, const Vec<dim>& grad, const Vec<dim>&) {
    grid.level(n).force[k] -= S[p] * grad;
  });
  grid.push(grid.per_level(&SparseGrid<dim>::force));
}

template <int dim>
void pull_velocities(AdaptiveGrid<dim>& grid, const TransferScheme& scheme) {
  grid.pull_velocity(scheme.uses_old_velocity());
}

template <int dim>
void grid_to_particles(Particles<dim>& P, const TransferScheme& scheme, const AdaptiveGrid<dim>& grid, double dt,
                       std::vector<Mat<dim>>* F, const ParticleGroupUpdate* then) {
  MPM_ASSERT(grid.particle_count() == P.size());
  const bool apic = scheme.type == TransferScheme::Type::apic;
  // The uniform loops' C_p has neither the ghosts' terms nor their D_p: the particles near
  // embedded ghosts add them, at their positions before the advection (a small copy: a
  // scratch of the terms themselves would cost more in fresh pages than their walk).
  const int groups = grid.regular_groups();
  std::vector<std::vector<Vec<dim>>> x_before(static_cast<std::size_t>(groups));
  for (int group = 0; apic && group < groups; ++group) {
    const std::vector<std::uint32_t>& near = grid.near_embedded(group).particle;
    x_before[group].resize(near.size());
    for (std::size_t i = 0; i < near.size(); ++i) x_before[group][i] = P.x[near[i]];
  }
  for (int group = 0; group < groups; ++group)
    mpm::grid_to_particles(P, grid.regular(group), grid.group_kernel(group), scheme,
                           grid.level(AdaptiveGrid<dim>::group_level(group)), dt, F, then);
  for (int group = 0; apic && group < groups; ++group) add_ghost_terms(P, grid, group, x_before[group]);
  gather_irregular(
      grid,
      [&](std::size_t p, int n) {
        // One walk over the particle's stencil: the velocity gradient for F, the PIC velocity,
        // and APIC's B_p and D_p with each embedded ghost's velocity moment Q_k and spread R_k
        // (or FLIP's velocity change). Each sum in the order of the walk.
        const SparseGrid<dim>& g = grid.level(n);
        const auto& ghosts = grid.ghosts(n);
        const Vec<dim> xp = P.x[p];
        Mat<dim> G = Mat<dim>::Zero(), B = Mat<dim>::Zero(), D = Mat<dim>::Zero();
        Vec<dim> v_pic = Vec<dim>::Zero(), dv = Vec<dim>::Zero();
        const auto add_node = [&](Index k, double w, const Vec<dim>& grad, const Vec<dim>& xk) {
          const Vec<dim>& vk = g.velocity[k];
          if (F) G.noalias() += vk * grad.transpose();
          v_pic += w * vk;
          if (!apic) {
            dv += w * (vk - g.velocity_old[k]);
            return;
          }
          const Vec<dim> r = xk - xp;
          B.noalias() += w * vk * r.transpose();
          D.noalias() += w * r * r.transpose();
          if (const int j = ghosts.of_node(k); j >= 0 && ghosts.moment[j] >= 0) {
            B += w * ghosts.velocity_moment[ghosts.moment[j]];
            D += w * ghosts.spread_of(ghosts.moment[j]);
          }
        };
        grid.for_each_weight(n, grid.half_cells(p), xp, add_node);
        if (F) (*F)[p] = (Mat<dim>::Identity() + dt * G) * (*F)[p];
        if (apic) {
          P.v[p] = v_pic;
          P.C[p] = B * D.inverse();
        } else {
          P.v[p] = scheme.flip_ratio * (P.v[p] + dv) + (1.0 - scheme.flip_ratio) * v_pic;
          P.C[p].setZero();
        }
        P.x[p] += dt * v_pic;
      },
      then);
}

template <int dim>
std::vector<RealWeight<dim>> real_weights(const AdaptiveGrid<dim>& grid, int n, double h, const Vec<dim>& x) {
  std::map<std::pair<int, Index>, RealWeight<dim>> sum;
  auto add = [&](int level, Index index, double w, const Vec<dim>& grad) {
    auto [it, inserted] = sum.try_emplace({level, index}, RealWeight<dim>{level, index, 0.0, Vec<dim>::Zero()});
    it->second.w += w;
    it->second.grad += grad;
  };
  const auto& ghosts = grid.ghosts(n);
  grid.for_each_weight(n, h, x, [&](Index k, double w, const Vec<dim>& grad, const Vec<dim>&) {
    const int j = ghosts.of_node(k);
    if (j < 0) return add(n, k, w, grad);
    for (std::uint32_t l = ghosts.begin[j]; l < ghosts.begin[j + 1]; ++l)
      add(ghosts.link[l].level, ghosts.link[l].index, ghosts.link[l].weight * w, ghosts.link[l].weight * grad);
  });
  std::vector<RealWeight<dim>> out;
  for (const auto& [key, rw] : sum) out.push_back(rw);
  return out;
}

#define MPM_INSTANTIATE(dim)                                                                                    \
  template void particles_to_grid(const Particles<dim>&, const TransferScheme&, AdaptiveGrid<dim>&,             \
                                  ParticleStress<dim>, double);                                                 \
  template void momentum_to_velocity(AdaptiveGrid<dim>&, const TransferScheme&);                                \
  template void stress_to_grid_forces(const std::vector<Mat<dim>>&, const Particles<dim>&, AdaptiveGrid<dim>&); \
  template void pull_velocities(AdaptiveGrid<dim>&, const TransferScheme&);                                     \
  template void grid_to_particles(Particles<dim>&, const TransferScheme&, const AdaptiveGrid<dim>&, double,     \
                                  std::vector<Mat<dim>>*, const ParticleGroupUpdate*);                          \
  template std::vector<RealWeight<dim>> real_weights(const AdaptiveGrid<dim>&, int, double, const Vec<dim>&);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::adaptive
