#pragma once
//! Private: the one rule by which the fluid stages call a cell fluid (it holds a particle), and
//! the operator box the pressure projection builds on it.
#include <fluid/pressure/cell_operator.h>

#include <mpm/core/sparse_grid.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace fluid::stages {

//! Grid cell holding x; on a periodic axis the canonical cell (in [periodic_lo, + period)).
template <int dim>
mpm::IVec<dim> fluid_cell_of(const mpm::SparseGrid<dim>& g, const mpm::Vec<dim>& x) {
  mpm::IVec<dim> c;
  for (int a = 0; a < dim; ++a)
    c[a] = std::clamp(static_cast<int>(std::floor((x[a] - g.origin()[a]) / g.dx())), 0, g.node_counts()[a] - 2);
  return g.periodic_image(c);
}

//! Calls f(local coordinate, local index) for every point of a box with `n` points per axis
//! (x fastest, so the index counts the points in order).
template <int dim, class Fn>
void for_each_point(const mpm::IVec<dim>& n, Fn&& f) {
  std::int64_t i = 0;
  mpm::for_each_in_box<dim>(mpm::IVec<dim>::Zero(), n - mpm::IVec<dim>::Ones(),
                            [&](const mpm::IVec<dim>& c) { f(c, i++); });
}

//! Makes `op` the node/cell operator box of the particles X (non-empty): the bounding box of
//! the cells holding a particle (the whole period along periodic axes), those cells fluid and
//! the others empty, no beta yet. Returns the grid cell of the box's cell (0, ...).
template <int dim>
mpm::IVec<dim> fluid_cell_box(const mpm::SparseGrid<dim>& g, const std::vector<mpm::Vec<dim>>& X,
                              CellOperator<dim>& op) {
  mpm::IVec<dim> lo = fluid_cell_of(g, X[0]), hi = lo;
  for (const mpm::Vec<dim>& x : X) {
    const mpm::IVec<dim> c = fluid_cell_of(g, x);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  for (int a = 0; a < dim; ++a) {
    op.periodic[a] = g.period()[a] > 0;
    if (!op.periodic[a]) continue;
    lo[a] = g.periodic_lo()[a];
    hi[a] = lo[a] + g.period()[a] - 1;
  }
  op.kind = CellOperator<dim>::Kind::node_cell;
  op.dx = g.dx();
  op.cells = hi - lo + mpm::IVec<dim>::Ones();
  op.type.assign(static_cast<std::size_t>(op.cell_count()), CellType::empty);
  for (const mpm::Vec<dim>& x : X) op.type[op.cell_index(fluid_cell_of(g, x) - lo)] = CellType::fluid;
  return lo;
}

//! A fluid cell whose corners all have beta = 0 (a particle inside a wall) has no unknown that
//! could change its divergence: it becomes empty (p = 0) instead of making the system
//! inconsistent.
template <int dim>
void drop_cells_without_unknowns(CellOperator<dim>& op) {
  for_each_point<dim>(op.cells, [&](const mpm::IVec<dim>& c, std::int64_t ci) {
    if (op.type[ci] != CellType::fluid) return;
    for (int k = 0; k < (1 << dim); ++k) {
      mpm::IVec<dim> n = c;
      for (int a = 0; a < dim; ++a) n[a] += (k >> a) & 1;
      if (op.beta[op.node_index(n)] > 0.0) return;
    }
    op.type[ci] = CellType::empty;
  });
}

}  // namespace fluid::stages
