#include <mpm/core/error.h>
#include <mpm/core/stages/resample_particles.h>
#include <mpm/core/stages/time_step_control.h>

namespace mpm::stages {

template <int dim>
void ResampleParticles<dim>::run(MpmState<dim>& s) {
  MPM_VERIFY(s.adaptive.has_value(), Error, "stage 'resample' needs an adaptive grid");
  if (!due(s)) return;
  ++resamplings_;
  const adaptive::ResampleCounts counts =
      adaptive::resample_particles(s.particles, s.adaptive->tree(), s.adaptive->points_per_axis(), settings_,
                                   deformation_, static_cast<std::uint64_t>(s.step), walls_);
  split_ += counts.split;
  merged_ += counts.merged;
  if (counts.split + counts.merged > 0) s.buckets = ParticleBuckets<dim>{};  // stale: the sort rebuilds them
}

template <int dim>
bool ResampleParticles<dim>::due(const MpmState<dim>& s) {
  if (settings_.max_travel <= 0.0) return s.step % settings_.every == 0;
  travel_ += s.dt * max_speed(s.particles.v);  // the last step's move (s.dt: its step, 0 before the first)
  if (travel_ < settings_.max_travel) return false;
  travel_ = 0.0;
  return true;
}

template class ResampleParticles<2>;
template class ResampleParticles<3>;

}  // namespace mpm::stages
