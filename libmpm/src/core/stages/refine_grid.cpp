#include <mpm/adaptive/particle_levels.h>
#include <mpm/adaptive/refinement.h>
#include <mpm/core/error.h>
#include <mpm/core/stages/refine_grid.h>

namespace mpm::stages {

template <int dim>
void RefineGrid<dim>::run(MpmState<dim>& s) {
  MPM_VERIFY(s.adaptive.has_value(), Error, "stage 'refine' needs an adaptive grid");
  adaptive::CellTree<dim>& tree = s.adaptive->tree();
  tree = static_tree_;
  adaptive::refine_around_particles(
      tree, s.particles.x, std::as_const(s.particles).template channel<std::uint16_t>(adaptive::kParticleLevel),
      padding_);
}

template class RefineGrid<2>;
template class RefineGrid<3>;

}  // namespace mpm::stages
