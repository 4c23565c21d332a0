// P2G (paper sec. 3.2, APIC: Jiang et al. 2015 eq. 10-11):
//   m_i = sum_p w_ip m_p,   (m v)_i = sum_p w_ip m_p (v_p + C_p (x_i - x_p)).
// Precondition: particles sorted into buckets for the current grid (stage 'sort').
#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/stages/particles_to_grid.h>

namespace mpm::stages {

template <int dim>
void ParticlesToGrid<dim>::run(MpmState<dim>& s) {
  if (s.adaptive)
    adaptive::particles_to_grid(s.particles, s.transfer, *s.adaptive);
  else
    particles_to_grid(s.particles, s.buckets, s.kernel, s.transfer, s.grid);
}

template class ParticlesToGrid<2>;
template class ParticlesToGrid<3>;

}  // namespace mpm::stages
