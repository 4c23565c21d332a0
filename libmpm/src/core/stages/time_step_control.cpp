// dt = min( cfl dx / max_p |v_p|,  wave_cfl dx / c,  max_dt,  t_frame_end - t )
// with c = sqrt((lambda + 2 mu) / rho) the p-wave speed of the stiffest material: explicit
// MPM is stable for dt < dx / c (Courant); the particle CFL keeps stencils from jumping cells.
// Enriched particle domains (domains/particle_domains.h) add wave_cfl h / c with h the
// thinnest enriched domain.
#include <mpm/core/stages/time_step_control.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace mpm::stages {

template <int dim>
double max_speed(const std::vector<Vec<dim>>& v) {
  return std::sqrt(tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, v.size(), 16384), 0.0,
      [&](const auto& r, double m) {
        for (std::size_t p = r.begin(); p != r.end(); ++p) m = std::max(m, v[p].squaredNorm());
        return m;
      },
      [](double a, double b) { return std::max(a, b); }));
}

template <int dim>
double TimeStepControl<dim>::stable_dt(const MpmState<dim>& s) const {
  const double speed = max_speed(s.particles.v);
  const double dx = finest_dx(s);
  double dt = settings_.max_dt;
  if (speed > 0.0) dt = std::min(dt, settings_.cfl * dx / speed);
  if (settings_.wave_speed > 0.0) {
    dt = std::min(dt, settings_.wave_cfl * dx / settings_.wave_speed);
    // Enriched particle domains are a Lagrangian mesh: their own Courant bound.
    if (s.domains && settings_.bound_enriched)
      dt = std::min(dt, settings_.wave_cfl * s.domains->enriched_length / settings_.wave_speed);
  }
  return dt;
}

template <int dim>
void TimeStepControl<dim>::run(MpmState<dim>& s) {
  s.dt = std::min(stable_dt(s), s.dt_limit);
}

template double max_speed(const std::vector<Vec<2>>&);
template double max_speed(const std::vector<Vec<3>>&);
template class TimeStepControl<2>;
template class TimeStepControl<3>;

}  // namespace mpm::stages
