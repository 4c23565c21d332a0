// For every node i with mass and every collider with phi(x_i, t+dt) <= 0:
//   v_rel = v_i - v_col;  sticky: v_rel = 0;  slip: v_rel -= (v_rel.n) n;
//   separate: if v_rel.n < 0, v_rel -= (v_rel.n) n and |v_t| -= mu |v_n| (Coulomb, >= 0);
//   v_i = v_rel + v_col.
// Applied after the explicit update so the positions advected in G2P respect the obstacles.
#include <mpm/core/stages/grid_boundary.h>

#include <tbb/parallel_for.h>

namespace mpm::stages {

template <int dim>
void GridBoundary<dim>::run(MpmState<dim>& s) {
  const double t = s.time + s.dt;
  for (SparseGrid<dim>* level : grid_levels(s)) {
    SparseGrid<dim>& g = *level;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.node_storage(), 1024), [&](const auto& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k)
        if (g.mass[k] > 0.0) colliders_.project(g.node_position(k), t, g.velocity[k]);
    });
  }
}

template class GridBoundary<2>;
template class GridBoundary<3>;

}  // namespace mpm::stages
