#include <coupling/stages/volume_fraction_stage.h>

#include <coupling/shared_nodes.h>
#include <cmath>

namespace coupling::stages {

template <int dim>
void VolumeFractionStage<dim>::run(CoupledState<dim>& s) {
  const mpm::SparseGrid<dim>& gs = s.sediment.grid;
  const double node_volume = std::pow(gs.dx(), dim);
  phi_.resize(gs.node_storage());
  for (std::size_t k = 0; k < phi_.size(); ++k) phi_[k] = gs.mass[k] / (rho_s_ * node_volume);
  if (s.has_fluid) {
    const mpm::SparseGrid<dim>& gw = s.fluid.grid;
    require_same_lattice(gs, gw, name());
    for_each_shared_node(gs, gw, [&](std::size_t ks, std::size_t kw) {
      const double grains = gs.mass[ks] / rho_s_, liquid = gw.mass[kw] / rho_w_;
      if (grains + liquid > 0.0) phi_[ks] = grains / (grains + liquid);
    });
  }
  s.fractions = clamp_fractions(phi_, min_fluid_);
}

template class VolumeFractionStage<2>;
template class VolumeFractionStage<3>;

}  // namespace coupling::stages
