#include <coupling/stages/bed_load.h>
#include <mpm/core/transfer.h>
#include <tbb/parallel_for.h>

namespace coupling::stages {

template <int dim>
void BedShear<dim>::run(CoupledState<dim>& s) {
  limited_ = limit_bed_shear(s.bed, s.fluid.grid, s.sediment.grid, s.dt);
  // The drift at the grains, gathered while they still sit where their P2G weights were taken
  // (so that sum_p m_p u_d(x_p) is the layer's sum_i m_i u_d,i).
  mpm::Particles<dim>& P = s.sediment.particles;
  s.bed.particle_drift.assign(P.size(), mpm::Vec<dim>::Zero());
  if (s.bed.nodes.empty()) return;
  for (int a = 0; a < dim; ++a) {
    if (a == s.bed.up) continue;
    node_drift_.assign(s.sediment.grid.node_storage(), 0.0);
    for (const BedLayerNode<dim>& n : s.bed.nodes) node_drift_[n.sediment] = s.bed.drift[std::size_t(n.column)][a];
    mpm::grid_to_scalar(node_drift_, P, s.sediment.buckets, s.sediment.kernel, s.sediment.grid, particle_drift_);
    for (std::size_t p = 0; p < P.size(); ++p) s.bed.particle_drift[p][a] = particle_drift_[p];
  }
}

template <int dim>
void BedLoadDrift<dim>::run(CoupledState<dim>& s) {
  mpm::Particles<dim>& P = s.sediment.particles;
  if (s.bed.particle_drift.size() != P.size()) return;  // no layer this step
  const double dt = s.dt, t = s.time + s.dt;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, P.size(), 4096), [&](const auto& r) {
    for (std::size_t p = r.begin(); p != r.end(); ++p) {
      if (s.bed.particle_drift[p].squaredNorm() == 0.0) continue;
      const mpm::Vec<dim> x = P.x[p] + dt * s.bed.particle_drift[p];
      if (!colliders_.prescribes(x, t)) P.x[p] = x;
    }
  });
}

template class BedShear<2>;
template class BedShear<3>;
template class BedLoadDrift<2>;
template class BedLoadDrift<3>;

}  // namespace coupling::stages
