// G2P (paper sec. 3.2; APIC: Jiang et al. 2015 eq. 8-9; FLIP blend: Zhu & Bridson 2005):
//   v_p^PIC = sum_i w_ip v_i,  APIC: C_p = (sum_i w_ip v_i (x_i - x_p)^T) D_p^-1
//   FLIP:   v_p = a (v_p + sum_i w_ip (v_i - v_i^old)) + (1 - a) v_p^PIC
//   x_p += dt v_p^PIC
// and, for a solid, the deformation update (sec. 3.2)  F_p <- (I + dt grad v_p) F_p,
// grad v_p = sum_i v_i (grad w_ip)^T, with the grid velocities after boundary conditions. On a
// uniform grid (and for the regular particles of an adaptive one) both come from one gather
// (transfer.h); the trial F^E of a plastic material is projected by the return map, right after
// each bucket's gather when the solver hands it over (stage 'g2p_plasticity').
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/finite_guard.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/transfer.h>

#include <atomic>

namespace mpm::stages {

template <int dim>
std::vector<std::string> GridToParticles<dim>::reads() const {
  std::vector<std::string> r{"grid.velocity", "particle.order"};
  if (!deformation_.empty()) r.push_back("particle." + deformation_);
  if (then_)
    for (const std::string& field : then_->reads()) r.push_back(field);
  return r;
}

template <int dim>
std::vector<std::string> GridToParticles<dim>::writes() const {
  std::vector<std::string> w{"particle.v", "particle.C", "particle.x"};
  if (!deformation_.empty()) w.push_back("particle." + deformation_);
  if (then_)
    for (const std::string& field : then_->writes()) w.push_back(field);
  return w;
}

template <int dim>
void GridToParticles<dim>::run(MpmState<dim>& s) {
  Particles<dim>& P = s.particles;
  std::vector<Mat<dim>>* F = deformation_.empty() ? nullptr : &P.template channel<Mat<dim>>(deformation_);
  // Each bucket's results are tested right after its gather, while in cache, and before
  // `then` changes F (which checks its own results); the search that names a particle runs
  // only when a bucket found a bad value.
  const ParticleGroupUpdate then = then_ ? then_->bind(s) : ParticleGroupUpdate{};
  std::atomic<bool> finite{true};
  const ParticleGroupUpdate after = [&](const std::uint32_t* first, const std::uint32_t* last) {
    if (!all_finite_at(P.v, first, last) || (F && !all_finite_at(*F, first, last)))
      finite.store(false, std::memory_order_relaxed);
    if (then) then(first, last);
  };
  if (s.adaptive)
    adaptive::grid_to_particles(P, s.transfer, *s.adaptive, s.dt, F, &after);
  else
    grid_to_particles(P, s.buckets, s.kernel, s.transfer, s.grid, s.dt, F, &after);
  if (!finite.load()) check_results(P, F);
  if (then_) then_->finish(s);
}

template <int dim>
void GridToParticles<dim>::check_results(const Particles<dim>& P, const std::vector<Mat<dim>>* F) const {
  if (F) check_finite(*F, name(), "particle", "deformation gradient F");
  check_finite(P.v, name(), "particle", "velocity");
}

template class GridToParticles<2>;
template class GridToParticles<3>;

}  // namespace mpm::stages
