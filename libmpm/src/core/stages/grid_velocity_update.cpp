// Symplectic Euler on the grid (paper sec. 3.2):
//   v_i^n     = (m v)_i / m_i                    (kept as v_i^old for FLIP)
//   v_i^{n+1} = v_i^n + dt (f_i / m_i + g)   (f_i already in (m v)_i where p2g added it)
// Nodes without mass keep zero velocity. Non-finite results stop the run naming the node.
#include <mpm/core/error.h>
#include <mpm/core/stages/grid_velocity_update.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <limits>

namespace mpm::stages {

template <int dim>
void GridVelocityUpdate<dim>::run(MpmState<dim>& s) {
  for (SparseGrid<dim>* level : grid_levels(s)) update(*level, s);
}

template <int dim>
void GridVelocityUpdate<dim>::update(SparseGrid<dim>& g, const MpmState<dim>& s) const {
  momentum_to_velocity(g, s.transfer);
  // An empty force channel: the p2g scatter added the forces to the momentum (transfer.h).
  const bool forces = with_forces_ && !g.force.empty();
  MPM_VERIFY(!forces || g.force.size() == g.node_storage(), Error,
             "stage '" + name() + "': the grid's forces do not match its nodes");
  const double dt = s.dt;
  const Vec<dim> dv_gravity = dt * s.gravity;
  // The finite check rides in the same pass; the smallest offending node is reported, so the
  // message does not depend on the thread count.
  std::atomic<std::size_t> first_bad{std::numeric_limits<std::size_t>::max()};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.node_storage(), 4096), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      if (!(g.mass[k] <= 0.0)) {  // a NaN mass too: the check below must see what it does
        if (forces) g.velocity[k] += (dt / g.mass[k]) * g.force[k];
        g.velocity[k] += dv_gravity;
      }
      if (!g.velocity[k].allFinite()) {
        std::size_t seen = first_bad.load(std::memory_order_relaxed);
        while (k < seen && !first_bad.compare_exchange_weak(seen, k, std::memory_order_relaxed)) {
        }
      }
    }
  });
  if (const std::size_t k = first_bad.load(); k != std::numeric_limits<std::size_t>::max()) {
    const IVec<dim> node = g.node_coord(k);
    std::string where;
    for (int a = 0; a < dim; ++a) where += (a ? ", " : "") + std::to_string(node[a]);
    throw NumericalError("stage '" + name() + "': grid node (" + where +
                         ") of the grid with dx = " + std::to_string(g.dx()) + " m has non-finite velocity (mass " +
                         std::to_string(g.mass[k]) + " kg)");
  }
}

template class GridVelocityUpdate<2>;
template class GridVelocityUpdate<3>;

}  // namespace mpm::stages
