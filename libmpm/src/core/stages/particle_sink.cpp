// Outflow (particle_sink.h): flag_p = [x_p in some region] (in parallel); the removed mass
// M_out += sum_{flagged p} m_p is summed in index order, so it does not depend on the thread
// count; then the flagged particles are erased from every channel, the others keep their order.
#include <mpm/core/stages/particle_sink.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <limits>

namespace mpm::stages {

template <int dim>
SinkRegion<dim> face_region(const Vec<dim>& lo, const Vec<dim>& hi, int axis, geometry::Side side, double depth) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  SinkRegion<dim> r{Vec<dim>::Constant(-inf), Vec<dim>::Constant(inf)};
  if (side == geometry::Side::upper)
    r.lo[axis] = hi[axis] - depth;
  else
    r.hi[axis] = lo[axis] + depth;
  return r;
}

template <int dim>
void ParticleSink<dim>::run(MpmState<dim>& s) {
  const auto& X = s.particles.x;
  flagged_.assign(X.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, X.size(), 1 << 14), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p)
      for (const SinkRegion<dim>& region : regions_)
        if (region.contains(X[p])) {
          flagged_[p] = 1;
          break;
        }
  });
  double mass = 0.0;
  for (std::size_t p = 0; p < X.size(); ++p)
    if (flagged_[p]) mass += s.particles.mass[p];
  const std::size_t removed = s.particles.erase_flagged(flagged_);
  if (removed == 0) return;
  removed_mass_ += mass;
  removed_count_ += removed;
  s.buckets = ParticleBuckets<dim>{};  // stale: the sort that follows rebuilds them
}

template SinkRegion<2> face_region(const Vec<2>&, const Vec<2>&, int, geometry::Side, double);
template SinkRegion<3> face_region(const Vec<3>&, const Vec<3>&, int, geometry::Side, double);
template class ParticleSink<2>;
template class ParticleSink<3>;

}  // namespace mpm::stages
