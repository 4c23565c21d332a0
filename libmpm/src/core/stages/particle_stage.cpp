#include <mpm/core/stages/particle_stage.h>

#include <tbb/parallel_for.h>

#include <array>
#include <cstdint>
#include <numeric>

namespace mpm::stages {

template <int dim>
void ParticleStage<dim>::run(MpmState<dim>& s) {
  const ParticleGroupUpdate update = bind(s);
  constexpr std::size_t group = 4096;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, s.particles.size(), group), [&](const auto& r) {
    std::array<std::uint32_t, group> index;
    for (std::size_t first = r.begin(); first < r.end(); first += group) {
      const std::size_t n = std::min(group, r.end() - first);
      std::iota(index.begin(), index.begin() + n, static_cast<std::uint32_t>(first));
      update(index.data(), index.data() + n);
    }
  });
  finish(s);
}

template class ParticleStage<2>;
template class ParticleStage<3>;

}  // namespace mpm::stages
