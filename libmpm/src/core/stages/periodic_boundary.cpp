// Periodic axes (definitions in periodic_boundary.h). With N cells per period the grid node j
// (canonical, periodic_lo <= j < periodic_lo + N) and every ghost node j + k N carry one
// degree of freedom: P2G sums over all copies (fold), every later stage sees the sum on each
// copy, and the stages that solve on the canonical nodes only (viscosity, pressure) hand their
// result back to the ghosts through the fill. Precondition: the allocated blocks are closed
// under images (SparseGrid::activate).
#include <mpm/core/error.h>
#include <mpm/core/stages/periodic_boundary.h>

#include <cmath>

namespace mpm::stages {

namespace {
//! Calls f(ghost storage index, image storage index) for every allocated ghost node.
template <int dim, class Fn>
void for_each_ghost(const SparseGrid<dim>& g, Fn&& f) {
  for (std::size_t k = 0; k < g.node_storage(); ++k) {
    const IVec<dim> node = g.node_coord(k);
    const IVec<dim> image = g.periodic_image(node);
    if (image == node) continue;
    const Index i = g.node_index(image);
    verify<NumericalError>(i >= 0, "periodic grid: the image of an allocated ghost node is not allocated");
    f(k, static_cast<std::size_t>(i));
  }
}
}  // namespace

template <int dim>
void PeriodicFold<dim>::run(MpmState<dim>& s) {
  SparseGrid<dim>& g = s.grid;
  for_each_ghost(g, [&](std::size_t ghost, std::size_t image) {
    g.mass[image] += g.mass[ghost];
    g.velocity[image] += g.velocity[ghost];
  });
  for_each_ghost(g, [&](std::size_t ghost, std::size_t image) {
    g.mass[ghost] = g.mass[image];
    g.velocity[ghost] = g.velocity[image];
  });
}

template <int dim>
void PeriodicFill<dim>::run(MpmState<dim>& s) {
  SparseGrid<dim>& g = s.grid;
  const bool old = !g.velocity_old.empty();
  for_each_ghost(g, [&](std::size_t ghost, std::size_t image) {
    g.velocity[ghost] = g.velocity[image];
    if (old) g.velocity_old[ghost] = g.velocity_old[image];
  });
}

template <int dim>
void PeriodicWrap<dim>::run(MpmState<dim>& s) {
  const SparseGrid<dim>& g = s.grid;
  for (int a = 0; a < dim; ++a) {
    if (g.period()[a] == 0) continue;
    const double lo = g.origin()[a] + SparseGrid<dim>::periodic_margin * g.dx();
    const double length = g.period()[a] * g.dx();
    for (Vec<dim>& x : s.particles.x) {
      if (x[a] >= lo && x[a] < lo + length) continue;
      double r = x[a] - lo;
      r -= length * std::floor(r / length);
      x[a] = lo + (r < length ? r : 0.0);  // r rounds up to length for a tiny negative x - lo
    }
  }
}

template class PeriodicFold<2>;
template class PeriodicFold<3>;
template class PeriodicFill<2>;
template class PeriodicFill<3>;
template class PeriodicWrap<2>;
template class PeriodicWrap<3>;

}  // namespace mpm::stages
