#include <mpm/adaptive/particle_levels.h>

#include <array>
#include <cmath>
#include <deque>
#include <map>

namespace mpm::adaptive {

template <int dim>
std::vector<std::uint16_t>& add_level_channel(Particles<dim>& particles, const CellTree<dim>& tree) {
  return particles.template add_channel<std::uint16_t>(kParticleLevel, static_cast<std::uint16_t>(tree.finest()),
                                                       ChannelUse{true, true, ""});
}

template <int dim>
LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>& tree, const std::vector<Vec<dim>>& fine,
                                                 double fine_volume, int points_per_axis, int surface_steps) {
  LevelledParticles<dim> out;
  std::vector<bool> keep_fine(fine.size(), false);
  if (surface_steps > 0) {
    const std::vector<int> d = lattice_surface_distance(fine, tree.dx(tree.finest()) / points_per_axis);
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

template <int dim>
std::vector<int> lattice_surface_distance(const std::vector<Vec<dim>>& x, double h) {
  auto site = [&](const Vec<dim>& p) {
    std::array<int, dim> i;
    for (int a = 0; a < dim; ++a) i[a] = static_cast<int>(std::floor(p[a] / h));
    return i;
  };
  std::map<std::array<int, dim>, std::size_t> index;
  for (std::size_t p = 0; p < x.size(); ++p) index.emplace(site(x[p]), p);
  // Multi-source breadth-first search from the particles with an empty face neighbour.
  std::vector<int> d(x.size(), 0);
  std::deque<std::size_t> queue;
  for (const auto& [i, p] : index) {
    for (int a = 0; a < dim && d[p] == 0; ++a)
      for (int s : {-1, 1}) {
        std::array<int, dim> j = i;
        j[a] += s;
        if (!index.count(j)) d[p] = 1;
      }
    if (d[p] == 1) queue.push_back(p);
  }
  while (!queue.empty()) {
    const std::size_t p = queue.front();
    queue.pop_front();
    const std::array<int, dim> i = site(x[p]);
    for (int a = 0; a < dim; ++a)
      for (int s : {-1, 1}) {
        std::array<int, dim> j = i;
        j[a] += s;
        const auto it = index.find(j);
        if (it != index.end() && d[it->second] == 0) {
          d[it->second] = d[p] + 1;
          queue.push_back(it->second);
        }
      }
  }
  return d;
}

#define MPM_INSTANTIATE(dim)                                                                                    \
  template std::vector<std::uint16_t>& add_level_channel(Particles<dim>&, const CellTree<dim>&);                \
  template LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>&, const std::vector<Vec<dim>>&, \
                                                            double, int, int);                                  \
  template std::vector<int> lattice_surface_distance(const std::vector<Vec<dim>>&, double);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::adaptive
