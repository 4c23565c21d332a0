// Sort: key_p = block of the first stencil node of x_p; counting sort by key (skipped when the
// order still holds, the common case between steps); grid blocks = every block a bucket's
// patch overlaps. Precondition: every particle inside the grid, finite.
#include <mpm/adaptive/particle_levels.h>
#include <mpm/core/stages/sort_particles.h>

namespace mpm::stages {

template <int dim>
void SortParticles<dim>::run(MpmState<dim>& s) {
  if (s.adaptive)  // transfer levels, level grids and ghost tables (adaptive_grid.h)
    s.adaptive->prepare(s.particles.x, s.particles.template channel<std::uint16_t>(adaptive::kParticleLevel), name(),
                        [&](const std::vector<std::uint32_t>& order) { s.particles.permute(order); });
  else
    sort_into_buckets(s.particles, s.kernel, s.grid, s.buckets, name());
}

template class SortParticles<2>;
template class SortParticles<3>;

}  // namespace mpm::stages
