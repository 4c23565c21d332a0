#include <mpm/adaptive/particle_levels.h>
#include <mpm/core/error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

namespace mpm::adaptive {

template <int dim>
std::vector<std::uint16_t>& add_level_channel(Particles<dim>& particles, const CellTree<dim>& tree) {
  return particles.template add_channel<std::uint16_t>(kParticleLevel, static_cast<std::uint16_t>(tree.finest()),
                                                       ChannelUse{true, true, ""});
}

template <int dim>
LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>& tree, const std::vector<Vec<dim>>& fine,
                                                 double fine_volume, int points_per_axis, int surface_steps,
                                                 const LatticeWalls<dim>& walls) {
  LevelledParticles<dim> out;
  std::vector<bool> keep_fine(fine.size(), false);
  if (surface_steps > 0) {
    const std::vector<int> d = lattice_surface_distance(fine, tree.dx(tree.finest()) / points_per_axis, walls);
    for (std::size_t p = 0; p < fine.size(); ++p) keep_fine[p] = d[p] <= surface_steps;
  }
  std::vector<int> leaf_level(fine.size());
  for (std::size_t p = 0; p < fine.size(); ++p) leaf_level[p] = tree.leaf_at(fine[p]).level;
  std::vector<bool> merged(fine.size(), false);
  for (int q = 0; q < tree.finest(); ++q) {
    const double h = tree.dx(q) / points_per_axis;  // sub-cell of a level-q cell
    const std::size_t full = static_cast<std::size_t>(ipow(1 << (tree.finest() - q), dim));
    std::map<std::array<int, dim>, std::vector<std::size_t>> groups;
    for (std::size_t p = 0; p < fine.size(); ++p) {
      if (merged[p] || keep_fine[p] || leaf_level[p] < 0 || leaf_level[p] > q) continue;
      std::array<int, dim> key;
      for (int a = 0; a < dim; ++a) key[a] = static_cast<int>(std::floor((fine[p][a] - tree.origin()[a]) / h));
      groups[key].push_back(p);
    }
    for (const auto& [key, members] : groups) {
      if (members.size() != full) continue;
      Vec<dim> mean = Vec<dim>::Zero();
      for (std::size_t p : members) {
        mean += fine[p];
        merged[p] = true;
      }
      out.x.push_back(mean / static_cast<double>(members.size()));
      out.volume.push_back(fine_volume * static_cast<double>(members.size()));
      out.level.push_back(static_cast<std::uint16_t>(q));
    }
  }
  for (std::size_t p = 0; p < fine.size(); ++p)
    if (!merged[p]) {
      out.x.push_back(fine[p]);
      out.volume.push_back(fine_volume);
      out.level.push_back(static_cast<std::uint16_t>(tree.finest()));
    }
  return out;
}

namespace {
constexpr int kSiteBits = 21;  // bits per axis of a packed site key (2D and 3D)
}  // namespace

namespace {
//! The breadth-first search of manhattan_depth over the distinct sites `unique` (indices into
//! `sites`); find(i) is the index of the first entry of site i, or -1 when i holds none.
template <int dim, class Find>
std::vector<int> depth_search(const std::vector<IVec<dim>>& sites, const std::vector<int>& unique, Find&& find,
                              int max_depth) {
  std::vector<int> depth(sites.size(), 0);
  std::vector<int> queue;  // every site enters once: a vector with a read cursor
  queue.reserve(unique.size());
  auto for_each_neighbour = [&](const IVec<dim>& i, auto&& fn) {
    for (int a = 0; a < dim; ++a)
      for (int s : {-1, 1}) {
        IVec<dim> j = i;
        j[a] += s;
        fn(find(j));
      }
  };
  for (const int i : unique) {  // the sources: sites with an empty face neighbour (-1; -2: beyond a wall)
    bool surface = false;
    for_each_neighbour(sites[i], [&](int j) { surface = surface || j == -1; });
    if (surface) {
      depth[i] = 1;
      queue.push_back(i);
    }
  }
  for (std::size_t next = 0; next < queue.size(); ++next) {
    const int i = queue[next];
    if (depth[i] > max_depth) continue;
    for_each_neighbour(sites[i], [&](int j) {
      if (j >= 0 && depth[j] == 0) {
        depth[j] = depth[i] + 1;
        queue.push_back(j);
      }
    });
  }
  return depth;
}
}  // namespace

template <int dim>
std::vector<int> manhattan_depth(const std::vector<IVec<dim>>& sites, int max_depth, const LatticeWalls<dim>& walls) {
  if (sites.empty()) return {};
  IVec<dim> lo = sites[0], hi = sites[0];
  for (const IVec<dim>& i : sites) {
    lo = lo.cwiseMin(i);
    hi = hi.cwiseMax(i);
  }
  const LatticeBox<dim> box(lo, hi);
  MPM_VERIFY((box.extent.array() < (1 << kSiteBits)).all(), Error,
             "manhattan_depth: the sites span more than 2^21 - 3 lattice steps on an axis");
  if (box.dense_for(sites.size())) {  // a compact set (a body)
    const int cap = box.cap(max_depth);
    std::vector<int> cells(static_cast<std::size_t>(box.cells()), 0);
    for (const IVec<dim>& i : sites) cells[box.flat(i)] = cap;
    manhattan_transform(box, cells, cap, walls);
    std::vector<int> depth(sites.size());
    for (std::size_t i = 0; i < sites.size(); ++i) depth[i] = cells[box.flat(sites[i])];  // <= cap <= max_depth + 1
    return depth;
  }
  // A sparse set: a breadth-first search over the distinct sites, found by hashed keys.
  auto key = [&](const IVec<dim>& i) {
    std::uint64_t k = 0;
    for (int a = dim - 1; a >= 0; --a) k = (k << kSiteBits) | static_cast<std::uint64_t>(i[a] - box.lo[a]);
    return k;
  };
  std::vector<int> first(sites.size()), unique;
  std::unordered_map<std::uint64_t, int> id;  // site key -> index of its first entry
  id.reserve(sites.size());
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const auto [it, inserted] = id.emplace(key(sites[i]), static_cast<int>(i));
    if (inserted) unique.push_back(it->second);
    first[i] = it->second;
  }
  std::vector<int> depth = depth_search<dim>(
      sites, unique,
      [&](const IVec<dim>& j) {
        if (walls.beyond(j)) return -2;
        const auto it = id.find(key(j));
        return it == id.end() ? -1 : it->second;
      },
      max_depth);
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const int d = depth[first[i]];
    depth[i] = (d == 0 || d > max_depth) ? max_depth + 1 : d;
  }
  return depth;
}

template <int dim>
void manhattan_transform(const LatticeBox<dim>& box, std::vector<int>& depth, int cap, const LatticeWalls<dim>& walls) {
  const std::size_t cells = depth.size();
  MPM_VERIFY(static_cast<double>(cells) == box.cells() && cap < std::numeric_limits<int>::max(), Error,
             "manhattan_transform: one depth per cell of the box and a cap below the largest int");
  const IVec<dim>& extent = box.extent;
  const IVec<dim> last = box.lo + extent - IVec<dim>::Ones();
  if (walls.beyond(box.lo) || walls.beyond(last))
    for_each_in_box<dim>(box.lo, last, [&](const IVec<dim>& i) {
      if (walls.beyond(i)) depth[box.flat(i)] = cap;
    });
  constexpr std::size_t chunk = 256;  // lines of a strided axis swept together (one vector loop)
  std::size_t stride = 1;             // cells between neighbours along axis a
  for (int a = 0; a < dim; ++a) {
    const std::size_t n = static_cast<std::size_t>(extent[a]);
    const std::size_t outer = cells / (stride * n), chunks = (stride + chunk - 1) / chunk;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, outer * chunks), [&](const auto& r) {
      for (std::size_t t = r.begin(); t != r.end(); ++t) {
        int* line = depth.data() + (t / chunks) * stride * n;
        const std::size_t i0 = (t % chunks) * chunk, i1 = std::min(stride, i0 + chunk);
        for (std::size_t k = 1; k < n; ++k)
          for (std::size_t i = i0; i < i1; ++i)
            line[k * stride + i] = std::min(line[k * stride + i], line[(k - 1) * stride + i] + 1);
        for (std::size_t k = n - 1; k-- > 0;)
          for (std::size_t i = i0; i < i1; ++i)
            line[k * stride + i] = std::min(line[k * stride + i], line[(k + 1) * stride + i] + 1);
      }
    });
    stride *= n;
  }
}

template <int dim>
std::vector<int> lattice_surface_distance(const std::vector<Vec<dim>>& x, double h, const LatticeWalls<dim>& walls) {
  std::vector<IVec<dim>> sites(x.size());
  for (std::size_t p = 0; p < x.size(); ++p)
    for (int a = 0; a < dim; ++a) sites[p][a] = static_cast<int>(std::floor(x[p][a] / h));
  return manhattan_depth(sites, std::numeric_limits<int>::max() - 1, walls);
}

#define MPM_INSTANTIATE(dim)                                                                                          \
  template std::vector<std::uint16_t>& add_level_channel(Particles<dim>&, const CellTree<dim>&);                      \
  template LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>&, const std::vector<Vec<dim>>&,       \
                                                            double, int, int, const LatticeWalls<dim>&);              \
  template std::vector<int> lattice_surface_distance(const std::vector<Vec<dim>>&, double, const LatticeWalls<dim>&); \
  template std::vector<int> manhattan_depth(const std::vector<IVec<dim>>&, int, const LatticeWalls<dim>&);            \
  template void manhattan_transform(const LatticeBox<dim>&, std::vector<int>&, int, const LatticeWalls<dim>&);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::adaptive
