#include <mpm/adaptive/particle_levels.h>

#include <array>
#include <cmath>
#include <map>

namespace mpm::adaptive {

template <int dim>
std::vector<std::uint16_t>& add_level_channel(Particles<dim>& particles, const CellTree<dim>& tree) {
  return particles.template add_channel<std::uint16_t>(kParticleLevel, static_cast<std::uint16_t>(tree.finest()),
                                                       ChannelUse{true, true, ""});
}

template <int dim>
LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>& tree, const std::vector<Vec<dim>>& fine,
                                                 double fine_volume, int points_per_axis) {
  LevelledParticles<dim> out;
  std::vector<int> leaf_level(fine.size());
  for (std::size_t p = 0; p < fine.size(); ++p) leaf_level[p] = tree.leaf_at(fine[p]).level;
  std::vector<bool> merged(fine.size(), false);
  for (int q = 0; q < tree.finest(); ++q) {
    const double h = tree.dx(q) / points_per_axis;  // sub-cell of a level-q cell
    const std::size_t full = static_cast<std::size_t>(ipow(1 << (tree.finest() - q), dim));
    std::map<std::array<int, dim>, std::vector<std::size_t>> groups;
    for (std::size_t p = 0; p < fine.size(); ++p) {
      if (merged[p] || leaf_level[p] < 0 || leaf_level[p] > q) continue;
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

#define MPM_INSTANTIATE(dim)                                                                                    \
  template std::vector<std::uint16_t>& add_level_channel(Particles<dim>&, const CellTree<dim>&);                \
  template LevelledParticles<dim> match_particles_to_leaves(const CellTree<dim>&, const std::vector<Vec<dim>>&, \
                                                            double, int);
MPM_INSTANTIATE(2)
MPM_INSTANTIATE(3)

}  // namespace mpm::adaptive
