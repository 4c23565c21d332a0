#include <mpm/core/error.h>
#include <mpm/core/stages/resample_particles.h>

namespace mpm::stages {

template <int dim>
void ResampleParticles<dim>::run(MpmState<dim>& s) {
  MPM_VERIFY(s.adaptive.has_value(), Error, "stage 'resample' needs an adaptive grid");
  if (s.step % settings_.every != 0) return;
  const adaptive::ResampleCounts counts =
      adaptive::resample_particles(s.particles, s.adaptive->tree(), s.adaptive->points_per_axis(), settings_,
                                   deformation_, static_cast<std::uint64_t>(s.step));
  split_ += counts.split;
  merged_ += counts.merged;
  if (counts.split + counts.merged > 0) s.buckets = ParticleBuckets<dim>{};  // stale: the sort rebuilds them
}

template class ResampleParticles<2>;
template class ResampleParticles<3>;

}  // namespace mpm::stages
