#pragma once
//! Private: the one rule by which the fluid stages call a cell fluid (it holds a particle).
#include <mpm/core/sparse_grid.h>

#include <algorithm>
#include <cmath>

namespace fluid::stages {

//! Grid cell holding x; on a periodic axis the canonical cell (in [periodic_lo, + period)).
template <int dim>
mpm::IVec<dim> fluid_cell_of(const mpm::SparseGrid<dim>& g, const mpm::Vec<dim>& x) {
  mpm::IVec<dim> c;
  for (int a = 0; a < dim; ++a)
    c[a] = std::clamp(static_cast<int>(std::floor((x[a] - g.origin()[a]) / g.dx())), 0, g.node_counts()[a] - 2);
  return g.periodic_image(c);
}

}  // namespace fluid::stages
