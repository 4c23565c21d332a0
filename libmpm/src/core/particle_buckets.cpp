#include <mpm/core/error.h>
#include <mpm/core/particle_buckets.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <sstream>

namespace mpm {

namespace {
template <int dim, class T>
std::string describe(const Eigen::Matrix<T, dim, 1>& x) {
  std::ostringstream s;
  s.precision(9);
  s << '(';
  for (int a = 0; a < dim; ++a) s << (a ? ", " : "") << x[a];
  s << ')';
  return s.str();
}

// First stencil node of a particle at cell coordinate xi; false when xi is not finite or the
// stencil leaves the grid (then `axis` is the offending axis, -1 for a non-finite position).
template <int dim, class T, class K>
bool stencil_base_in_grid(const K& kernel, const Eigen::Matrix<T, dim, 1>& xi, const IVec<dim>& node_counts,
                          IVec<dim>& base, int& axis) {
  axis = -1;
  if (!xi.allFinite()) return false;
  for (int a = 0; a < dim; ++a) {
    axis = a;
    // The bound keeps the floor inside int range before the kernel converts it.
    if (!(std::abs(static_cast<double>(xi[a])) < 1e9)) return false;
    double w[K::support], dw[K::support];
    kernel(static_cast<double>(xi[a]), base[a], w, dw);
    if (base[a] < 0 || base[a] + K::support > node_counts[a]) return false;
  }
  return true;
}

// Block keys, then a stable counting sort of the particle indices into `order` (left alone
// when the keys are already in storage order; the return value says which). Fills
// everything of `buckets` but the index and allocates the grid blocks.
template <int dim, class T>
bool order_by_block(const std::vector<Eigen::Matrix<T, dim, 1>>& x, const Kernel& kernel, SparseGrid<dim>& grid,
                    ParticleBuckets<dim>& buckets, const std::string& stage, std::vector<std::uint32_t>& order) {
  const std::size_t n = x.size();
  const CellMap<dim> map(grid);

  // Keys in parallel; an invalid particle is reported after the loop, the one with the
  // lowest index so that the message does not depend on the thread count.
  std::vector<BlockKey> key(n);
  std::atomic<std::size_t> first_bad{n};
  std::visit(
      [&](const auto& k) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const auto& r) {
          for (std::size_t p = r.begin(); p != r.end(); ++p) {
            IVec<dim> base;
            int axis;
            if (stencil_base_in_grid<dim, T>(k, map(x[p]), grid.node_counts(), base, axis)) {
              key[p] = grid.block_id(base);
            } else {
              std::size_t seen = first_bad.load();
              while (p < seen && !first_bad.compare_exchange_weak(seen, p)) {
              }
              key[p] = 0;
            }
          }
        });
        if (const std::size_t p = first_bad.load(); p < n) {
          IVec<dim> base;
          int axis;
          stencil_base_in_grid<dim, T>(k, map(x[p]), grid.node_counts(), base, axis);
          if (axis < 0)
            throw NumericalError("stage '" + stage + "': particle " + std::to_string(p) +
                                 " has a non-finite position " + describe<dim, T>(x[p]));
          throw NumericalError("stage '" + stage + "': particle " + std::to_string(p) + " at " +
                               describe<dim, T>(x[p]) + " left the grid domain (axis " + std::to_string(axis) +
                               "); keep particles inside the walls");
        }
      },
      kernel);

  // Stable sort by block key (a parallel counting sort by rank, block_table.h): its ranks are
  // the buckets.
  KeyOrder sorted = sort_keys(key);
  const bool in_order = sorted.identity;
  if (!in_order) order = std::move(sorted.order);
  buckets.begin = std::move(sorted.begin);
  buckets.block = std::move(sorted.key);
  for (auto& c : buckets.by_color) c.clear();

  // Every bucket touches its own block and the +1 neighbours on each axis.
  std::vector<BlockKey> blocks;
  blocks.reserve(buckets.block.size() * ParticleBuckets<dim>::colors);
  for (int b = 0; b < buckets.count(); ++b) {
    const IVec<dim> c = grid.block_coord(buckets.block[b]);
    int color = 0;
    for (int a = 0; a < dim; ++a) color |= (c[a] & 1) << a;
    buckets.by_color[color].push_back(b);
    for (int corner = 0; corner < ParticleBuckets<dim>::colors; ++corner) {
      IVec<dim> nb = c;
      for (int a = 0; a < dim; ++a) nb[a] += (corner >> a) & 1;
      blocks.push_back(grid.block_id(nb * SparseGrid<dim>::block_size));
    }
  }
  std::sort(blocks.begin(), blocks.end());
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  grid.activate(blocks);
  return in_order;
}

void identity(std::vector<std::uint32_t>& index, std::size_t n) {
  index.resize(n);
  std::iota(index.begin(), index.end(), std::uint32_t{0});
}

}  // namespace

bool scattered(const std::vector<std::uint32_t>& index) {
  std::size_t breaks = 0;
  for (std::size_t i = 1; i < index.size(); ++i) breaks += index[i] != index[i - 1] + 1;
  return 8 * breaks > index.size();
}

template <int dim>
IVec<dim> stencil_base(const SparseGrid<dim>& grid, const Kernel& kernel, const Vec<dim>& x) {
  const Vec<dim> xi = CellMap<dim>(grid)(x);
  return std::visit(
      [&](const auto& k) {
        IVec<dim> base;
        double w[4], dw[4];
        for (int a = 0; a < dim; ++a) k(xi[a], base[a], w, dw);
        return base;
      },
      kernel);
}

template <int dim, class T>
bool sort_into_buckets(const std::vector<Eigen::Matrix<T, dim, 1>>& x, const Kernel& kernel, SparseGrid<dim>& grid,
                       ParticleBuckets<dim>& buckets, const MoveParticles& move, const std::string& stage) {
  if (order_by_block(x, kernel, grid, buckets, stage, buckets.particle)) {
    identity(buckets.particle, x.size());
    return false;
  }
  if (!move || !scattered(buckets.particle)) return false;
  move(buckets.particle);
  identity(buckets.particle, x.size());
  return true;
}

template <int dim>
bool sort_into_buckets(Particles<dim>& particles, const Kernel& kernel, SparseGrid<dim>& grid,
                       ParticleBuckets<dim>& buckets, const std::string& stage) {
  return sort_into_buckets<dim, double>(
      particles.x, kernel, grid, buckets, [&](const std::vector<std::uint32_t>& order) { particles.permute(order); },
      stage);
}

template <int dim, class T>
std::vector<std::uint32_t> bucket_order(const std::vector<Eigen::Matrix<T, dim, 1>>& x, const Kernel& kernel,
                                        SparseGrid<dim>& grid, ParticleBuckets<dim>& buckets,
                                        const std::string& stage) {
  std::vector<std::uint32_t> order;
  order_by_block(x, kernel, grid, buckets, stage, order);
  identity(buckets.particle, x.size());
  return order;
}

#define MPM_INSTANTIATE_SCALAR(dim, T)                                                                           \
  template bool sort_into_buckets(const std::vector<Eigen::Matrix<T, dim, 1>>&, const Kernel&, SparseGrid<dim>&, \
                                  ParticleBuckets<dim>&, const MoveParticles&, const std::string&);              \
  template std::vector<std::uint32_t> bucket_order(const std::vector<Eigen::Matrix<T, dim, 1>>&, const Kernel&,  \
                                                   SparseGrid<dim>&, ParticleBuckets<dim>&, const std::string&);
#define MPM_INSTANTIATE(dim)                                                                               \
  template IVec<dim> stencil_base(const SparseGrid<dim>&, const Kernel&, const Vec<dim>&);                 \
  template bool sort_into_buckets(Particles<dim>&, const Kernel&, SparseGrid<dim>&, ParticleBuckets<dim>&, \
                                  const std::string&);                                                     \
  MPM_INSTANTIATE_SCALAR(dim, double)                                                                      \
  MPM_INSTANTIATE_SCALAR(dim, float)
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm
