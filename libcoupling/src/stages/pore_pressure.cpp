#include <coupling/stages/pore_pressure.h>

#include <coupling/shared_nodes.h>
#include <fluid/stages/equation_of_state.h>
#include <mpm/core/finite_guard.h>
#include <mpm/core/transfer.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace coupling::stages {

template <int dim>
void LiquidVolumeUpdate<dim>::run(CoupledState<dim>& s) {
  mpm::MpmState<dim>& liquid = s.fluid;
  const mpm::SparseGrid<dim>& gw = liquid.grid;
  const mpm::SparseGrid<dim>& gs = s.sediment.grid;
  require_same_lattice(gw, gs, name());
  // The mixture flux u = n_w v_w + n_s v_s and n_w on the liquid's nodes.
  node_fraction_.assign(gw.node_storage(), 1.0);
  flux_ = gw.velocity;
  for_each_shared_node(gw, gs, [&](std::size_t kw, std::size_t ks) {
    node_fraction_[kw] = s.fractions.fluid[ks];
    flux_[kw] = s.fractions.fluid[ks] * gw.velocity[kw] + s.fractions.sediment[ks] * gs.velocity[ks];
  });
  const mpm::Particles<dim>& P = liquid.particles;
  mpm::grid_to_scalar(node_fraction_, P, liquid.buckets, liquid.kernel, gw, particle_fraction_);
  mpm::node_field_gradient(P, liquid.buckets, liquid.kernel, gw, flux_, grad_flux_);
  std::vector<double>& own = liquid.particles.template channel<double>(fluid::kLiquidVolumeRatio);
  const double dt = s.dt;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, own.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p)
      own[p] *= 1.0 + dt * grad_flux_[p].trace() / particle_fraction_[p];
  });
  mpm::check_finite(own, name(), "fluid particle", "liquid volume ratio");
}

template <int dim>
void PorePressureShare<dim>::run(CoupledState<dim>& s) {
  mpm::SparseGrid<dim>& gw = s.fluid.grid;
  mpm::SparseGrid<dim>& gs = s.sediment.grid;
  const double dt = s.dt;
  for_each_shared_node(gw, gs, [&](std::size_t kw, std::size_t ks) {
    if (!(gw.mass[kw] > 0.0) || !(gs.mass[ks] > 0.0)) return;
    const mpm::Vec<dim> impulse = (dt * s.fractions.sediment[ks]) * gw.force[kw];
    gw.velocity[kw] -= impulse / gw.mass[kw];
    gs.velocity[ks] += impulse / gs.mass[ks];
  });
}

template class LiquidVolumeUpdate<2>;
template class LiquidVolumeUpdate<3>;
template class PorePressureShare<2>;
template class PorePressureShare<3>;

}  // namespace coupling::stages
