// G2P (paper sec. 3.2; APIC: Jiang et al. 2015 eq. 8-9; FLIP blend: Zhu & Bridson 2005):
//   v_p^PIC = sum_i w_ip v_i,  APIC: C_p = (sum_i w_ip v_i (x_i - x_p)^T) D_p^-1
//   FLIP:   v_p = a (v_p + sum_i w_ip (v_i - v_i^old)) + (1 - a) v_p^PIC
//   x_p += dt v_p^PIC
// Precondition: grid velocities after boundary conditions.
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/finite_guard.h>
#include <mpm/core/stages/grid_to_particles.h>

namespace mpm::stages {

template <int dim>
void GridToParticles<dim>::run(MpmState<dim>& s) {
  if (s.adaptive)
    adaptive::grid_to_particles(s.particles, s.transfer, *s.adaptive, s.dt);
  else
    grid_to_particles(s.particles, s.buckets, s.kernel, s.transfer, s.grid, s.dt);
  check_finite(s.particles.v, name(), "particle", "velocity");
}

template class GridToParticles<2>;
template class GridToParticles<3>;

}  // namespace mpm::stages
