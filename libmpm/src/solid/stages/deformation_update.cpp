// Deformation update (paper sec. 3.2):  F_p^{n+1} = (I + dt grad v_p^{n+1}) F_p^n,
// grad v_p = sum_i v_i^{n+1} (grad w_ip)^T, with the grid velocities after boundary conditions.
// The trial F^E of a plastic material is projected afterwards by stage 'plasticity'.
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/finite_guard.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/stages/deformation_update.h>

#include <tbb/parallel_for.h>

namespace mpm::stages {

template <int dim>
void DeformationUpdate<dim>::run(MpmState<dim>& s) {
  Particles<dim>& P = s.particles;
  std::vector<Mat<dim>>& F = solid::elastic_F(P);
  if (s.adaptive)
    adaptive::velocity_gradient(P, *s.adaptive, grad_v_);
  else
    velocity_gradient(P, s.buckets, s.kernel, s.grid, grad_v_);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) F[p] = (Mat<dim>::Identity() + s.dt * grad_v_[p]) * F[p];
  });
  check_finite(F, name(), "particle", "deformation gradient F");
}

template class DeformationUpdate<2>;
template class DeformationUpdate<3>;

}  // namespace mpm::stages
