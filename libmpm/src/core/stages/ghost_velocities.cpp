#include <mpm/adaptive/adaptive_transfer.h>
#include <mpm/core/error.h>
#include <mpm/core/stages/ghost_velocities.h>

namespace mpm::stages {

template <int dim>
void GhostVelocities<dim>::run(MpmState<dim>& s) {
  MPM_VERIFY(s.adaptive.has_value(), Error, "stage 'ghost_velocities' needs an adaptive grid");
  adaptive::pull_velocities(*s.adaptive, s.transfer);
}

template class GhostVelocities<2>;
template class GhostVelocities<3>;

}  // namespace mpm::stages
