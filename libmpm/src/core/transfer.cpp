#include <mpm/core/detail/transfer_loops.h>
#include <mpm/core/error.h>
#include <mpm/core/transfer.h>

namespace mpm {

using detail::ChannelView;
using detail::component_view;
using detail::PatchFrame;
using detail::scalar_view;
using detail::Stencil;

template <int dim>
std::array<ChannelView, dim> vector_views(const std::vector<Vec<dim>>& v) {
  std::array<ChannelView, dim> views;
  for (int a = 0; a < dim; ++a) views[a] = component_view<dim>(v, a);
  return views;
}

namespace {
// out_i -= sum_p S_p grad w_ip for the particles of one group (out sized to the node storage).
template <int dim>
void add_stress_to_nodes(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& P,
                         const BucketGroup<dim>& group, const SparseGrid<dim>& g, std::vector<Vec<dim>>& out) {
  std::array<ChannelView, dim> channels;
  for (int a = 0; a < dim; ++a) channels[a] = component_view<dim>(out, a);
  const double inv_dx = 1.0 / g.dx();
  // The set-up of a chunk of particles (weights, -S / dx) at once, as in P2G (detail::in_chunks).
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::scatter_buckets<dim, dim>(
            g, *group.buckets, channels,
            [&](const std::uint32_t* first, const std::uint32_t* last, const PatchFrame<dim>& f, double* patch) {
              Stencil<dim, K::support> st[detail::chunk_size];
              Mat<dim> A[detail::chunk_size];
              detail::in_chunks(
                  first, last,
                  [&](std::uint32_t p) {
                    detail::prefetch(P.x[p]);
                    detail::prefetch(weighted_stress[p]);
                  },
                  [&](std::uint32_t p, int q) {
                    st[q].compute(k, f.cells(P.x[p]), f.origin);
                    A[q] = -inv_dx * weighted_stress[p];
                  },
                  [&](std::uint32_t, int q) { detail::spread_gradient<dim>(st[q], A[q], patch, 0); });
            });
      },
      group.kernel);
}
}  // namespace

template <int dim>
void particles_to_grid(const Particles<dim>& particles, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                       const TransferScheme& scheme, SparseGrid<dim>& grid,
                       std::type_identity_t<ParticleStress<dim>> stress, double impulse_dt) {
  const BucketGroup<dim> group{&buckets, kernel};
  particles_to_grid(particles, std::span<const BucketGroup<dim>>(&group, 1), scheme, grid, stress, impulse_dt);
}

template <int dim>
void particles_to_grid(const Particles<dim>& particles, std::span<const BucketGroup<dim>> groups,
                       const TransferScheme& scheme, SparseGrid<dim>& grid,
                       std::type_identity_t<ParticleStress<dim>> stress, double impulse_dt) {
  MPM_VERIFY(!stress || stress.count == particles.size(), Error,
             "particles_to_grid: the stresses (and their weights) need one entry per particle");
  std::fill(grid.mass.begin(), grid.mass.end(), 0.0);
  const bool impulse = stress && impulse_dt > 0.0;
  MPM_VERIFY(!impulse || !scheme.uses_old_velocity(), Error,
             "particles_to_grid: stress impulses in the momentum would enter FLIP's v_old");
  if (impulse) std::vector<Vec<dim>>().swap(grid.force);  // the forces are in the momentum
  std::fill(grid.velocity.begin(), grid.velocity.end(), Vec<dim>::Zero());
  const bool force_channel = stress && !impulse;
  if (force_channel) grid.force.assign(grid.node_storage(), Vec<dim>::Zero());
  const auto run = [&](auto channel_count, const BucketGroup<dim>& group) {
    constexpr std::size_t Ch = decltype(channel_count)::value;
    std::array<ChannelView, Ch> channels;
    channels[0] = scalar_view(grid.mass);
    for (int a = 0; a < dim; ++a) channels[a + 1] = component_view<dim>(grid.velocity, a);
    const Mat<dim>* S = impulse ? stress.tau : nullptr;
    if constexpr (Ch > dim + 1) {
      for (int a = 0; a < dim; ++a) channels[dim + 1 + a] = component_view<dim>(grid.force, a);
      S = stress.tau;
    }
    std::visit(
        [&](const auto& k) {
          using K = std::decay_t<decltype(k)>;
          if (scheme.type == TransferScheme::Type::apic)
            detail::p2g<dim, K, true>(particles, *group.buckets, k, grid, channels, S, impulse_dt, stress.weight);
          else
            detail::p2g<dim, K, false>(particles, *group.buckets, k, grid, channels, S, impulse_dt, stress.weight);
        },
        group.kernel);
  };
  for (const BucketGroup<dim>& group : groups) {
    if (force_channel)
      run(std::integral_constant<std::size_t, 2 * dim + 1>{}, group);
    else
      run(std::integral_constant<std::size_t, dim + 1>{}, group);
  }
}

template <int dim>
void momentum_to_velocity(SparseGrid<dim>& grid, const TransferScheme& scheme) {
  const std::size_t n = grid.node_storage();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k)
      grid.velocity[k] = grid.mass[k] > 0.0 ? Vec<dim>(grid.velocity[k] / grid.mass[k]) : Vec<dim>::Zero();
  });
  if (scheme.uses_old_velocity())
    grid.velocity_old = grid.velocity;
  else
    grid.velocity_old.clear();
}

template <int dim>
void grid_to_particles(Particles<dim>& particles, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                       const TransferScheme& scheme, const SparseGrid<dim>& grid, double dt, std::vector<Mat<dim>>* F,
                       const ParticleGroupUpdate* then) {
  MPM_VERIFY(!F || F->size() == particles.size(), Error, "grid_to_particles: F needs one entry per particle");
  const std::array<ChannelView, dim> velocity = vector_views<dim>(grid.velocity);
  const auto run = [&](auto deform) {
    constexpr bool fused = decltype(deform)::value;
    Mat<dim>* f = fused ? F->data() : nullptr;
    std::visit(
        [&](const auto& k) {
          using K = std::decay_t<decltype(k)>;
          if (scheme.type == TransferScheme::Type::apic) {
            detail::g2p<dim, K, false, fused>(particles, buckets, k, grid, velocity, 0.0, dt, f, then);
          } else {
            std::array<ChannelView, 2 * dim> both;
            const std::array<ChannelView, dim> old = vector_views<dim>(grid.velocity_old);
            std::copy(velocity.begin(), velocity.end(), both.begin());
            std::copy(old.begin(), old.end(), both.begin() + dim);
            detail::g2p<dim, K, true, fused>(particles, buckets, k, grid, both, scheme.flip_ratio, dt, f, then);
          }
        },
        kernel);
  };
  if (F)
    run(std::true_type{});
  else
    run(std::false_type{});
}

template <int dim>
void velocity_gradient(const Particles<dim>& P, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                       const SparseGrid<dim>& grid, std::vector<Mat<dim>>& grad_v) {
  node_field_gradient(P, buckets, kernel, grid, grid.velocity, grad_v);
}

template <int dim>
void node_field_gradient(const Particles<dim>& P, const ParticleBuckets<dim>& buckets, const Kernel& kernel,
                         const SparseGrid<dim>& grid, const std::vector<Vec<dim>>& u, std::vector<Mat<dim>>& grad_v) {
  grad_v.resize(P.size());
  const double inv_dx = 1.0 / grid.dx();
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::gather<dim, dim>(grid, buckets, vector_views<dim>(u),
                                 [&](std::uint32_t p, const PatchFrame<dim>& f, const double* patch) {
                                   Stencil<dim, K::support> st;
                                   st.compute(k, f.cells(P.x[p]), f.origin);
                                   Mat<dim> g = Mat<dim>::Zero();
                                   st.for_each_node([&](int node, double, const Vec<dim>& grad, const Vec<dim>&) {
                                     g.noalias() += Eigen::Map<const Vec<dim>>(patch + node * dim) * grad.transpose();
                                   });
                                   grad_v[p] = g * inv_dx;
                                 });
      },
      kernel);
}

template <int dim>
void scalar_to_grid(const std::vector<double>& values, const Particles<dim>& P, const ParticleBuckets<dim>& buckets,
                    const Kernel& kernel, const SparseGrid<dim>& grid, std::vector<double>& out) {
  out.assign(grid.node_storage(), 0.0);
  using Node = Eigen::Matrix<double, 1, 1>;
  const std::array<detail::ChannelView, 1> channels{detail::scalar_view(out)};
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::scatter<dim, 1>(grid, buckets, channels, [&](std::uint32_t p, const PatchFrame<dim>& f, double* patch) {
          Stencil<dim, K::support> st;
          st.template compute<false>(k, f.cells(P.x[p]), f.origin);
          Node c[dim + 1];
          for (Node& ci : c) ci.setZero();
          c[0](0) = values[p];
          detail::spread<false>(st, c, patch);
        });
      },
      kernel);
}

template <int dim>
void grid_to_scalar(const std::vector<double>& values, const Particles<dim>& P, const ParticleBuckets<dim>& buckets,
                    const Kernel& kernel, const SparseGrid<dim>& grid, std::vector<double>& out) {
  out.resize(P.size());
  const std::array<ChannelView, 1> channels{scalar_view(values)};
  std::visit(
      [&](const auto& k) {
        using K = std::decay_t<decltype(k)>;
        detail::gather<dim, 1>(
            grid, buckets, channels, [&](std::uint32_t p, const PatchFrame<dim>& f, const double* patch) {
              Stencil<dim, K::support> st;
              st.template compute<false>(k, f.cells(P.x[p]), f.origin);
              double sum = 0.0;
              st.for_each_node([&](int node, double w, const Vec<dim>&, const Vec<dim>&) { sum += w * patch[node]; });
              out[p] = sum;
            });
      },
      kernel);
}

template <int dim>
void stress_to_grid_forces(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& P,
                           const ParticleBuckets<dim>& buckets, const Kernel& kernel, SparseGrid<dim>& g) {
  stress_to_nodes(weighted_stress, P, buckets, kernel, g, g.force);
}

template <int dim>
void stress_to_grid_forces(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& P,
                           std::span<const BucketGroup<dim>> groups, SparseGrid<dim>& g) {
  g.force.assign(g.node_storage(), Vec<dim>::Zero());
  for (const BucketGroup<dim>& group : groups) add_stress_to_nodes(weighted_stress, P, group, g, g.force);
}

template <int dim>
void stress_to_nodes(const std::vector<Mat<dim>>& weighted_stress, const Particles<dim>& P,
                     const ParticleBuckets<dim>& buckets, const Kernel& kernel, const SparseGrid<dim>& g,
                     std::vector<Vec<dim>>& out) {
  out.assign(g.node_storage(), Vec<dim>::Zero());
  add_stress_to_nodes(weighted_stress, P, BucketGroup<dim>{&buckets, kernel}, g, out);
}

#define MPM_INSTANTIATE(dim)                                                                                           \
  template void particles_to_grid(const Particles<dim>&, const ParticleBuckets<dim>&, const Kernel&,                   \
                                  const TransferScheme&, SparseGrid<dim>&, ParticleStress<dim>, double);               \
  template void particles_to_grid(const Particles<dim>&, std::span<const BucketGroup<dim>>, const TransferScheme&,     \
                                  SparseGrid<dim>&, ParticleStress<dim>, double);                                      \
  template void stress_to_grid_forces(const std::vector<Mat<dim>>&, const Particles<dim>&,                             \
                                      std::span<const BucketGroup<dim>>, SparseGrid<dim>&);                            \
  template void momentum_to_velocity(SparseGrid<dim>&, const TransferScheme&);                                         \
  template void grid_to_particles(Particles<dim>&, const ParticleBuckets<dim>&, const Kernel&, const TransferScheme&,  \
                                  const SparseGrid<dim>&, double, std::vector<Mat<dim>>*, const ParticleGroupUpdate*); \
  template void scalar_to_grid(const std::vector<double>&, const Particles<dim>&, const ParticleBuckets<dim>&,         \
                               const Kernel&, const SparseGrid<dim>&, std::vector<double>&);                           \
  template void grid_to_scalar(const std::vector<double>&, const Particles<dim>&, const ParticleBuckets<dim>&,         \
                               const Kernel&, const SparseGrid<dim>&, std::vector<double>&);                           \
  template void stress_to_grid_forces(const std::vector<Mat<dim>>&, const Particles<dim>&,                             \
                                      const ParticleBuckets<dim>&, const Kernel&, SparseGrid<dim>&);                   \
  template void velocity_gradient(const Particles<dim>&, const ParticleBuckets<dim>&, const Kernel&,                   \
                                  const SparseGrid<dim>&, std::vector<Mat<dim>>&);                                     \
  template void stress_to_nodes(const std::vector<Mat<dim>>&, const Particles<dim>&, const ParticleBuckets<dim>&,      \
                                const Kernel&, const SparseGrid<dim>&, std::vector<Vec<dim>>&);                        \
  template void node_field_gradient(const Particles<dim>&, const ParticleBuckets<dim>&, const Kernel&,                 \
                                    const SparseGrid<dim>&, const std::vector<Vec<dim>>&, std::vector<Mat<dim>>&);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm
