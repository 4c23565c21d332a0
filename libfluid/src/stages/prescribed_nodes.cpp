// mask_i = [m_i > 0 and (P(a) != a or P(-a) != -a)],  P = ColliderSet::project at (x_i, t),
// a = (1, 1/sqrt(2), 1/sqrt(3)) [m/s]: no obstacle normal used by the scenes is orthogonal to a.
#include <fluid/stages/prescribed_nodes.h>

#include <tbb/parallel_for.h>

#include <cmath>

namespace fluid::stages {

namespace {
//! The generic probe velocity a of the header comment [m/s].
template <int dim>
mpm::Vec<dim> probe() {
  mpm::Vec<dim> a;
  for (int d = 0; d < dim; ++d) a[d] = 1.0 / std::sqrt(d + 1.0);
  return a;
}
}  // namespace

template <int dim>
std::optional<mpm::Mat<dim>> slip_directions(const mpm::geometry::ColliderSet<dim>& colliders, const mpm::Vec<dim>& x,
                                             double t) {
  // A separating obstacle holds the probe that approaches it: of the two probes, the one with
  // fewer free directions tells what the obstacles hold.
  const mpm::Vec<dim> a = probe<dim>();
  const mpm::Mat<dim> up = colliders.free_directions(x, t, a), down = colliders.free_directions(x, t, -a);
  const mpm::Mat<dim> free = up.trace() <= down.trace() ? up : down;
  if (free.trace() < 0.5) return std::nullopt;  // the rank of an orthogonal projector
  return free;
}

template <int dim>
bool is_prescribed(const mpm::SparseGrid<dim>& grid, const mpm::geometry::ColliderSet<dim>& colliders, std::size_t k,
                   double t) {
  if (colliders.empty() || grid.mass[k] <= 0.0) return false;
  const mpm::Vec<dim> a = probe<dim>();
  const mpm::Vec<dim> x = grid.node_position(k);
  mpm::Vec<dim> up = a, down = -a;
  colliders.project(x, t, up);
  colliders.project(x, t, down);
  return up != a || down != -a;
}

template <int dim>
std::vector<std::uint8_t> prescribed_nodes(const mpm::SparseGrid<dim>& grid,
                                           const mpm::geometry::ColliderSet<dim>& colliders, double t) {
  std::vector<std::uint8_t> mask(grid.node_storage(), 0);
  if (colliders.empty()) return mask;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.node_storage(), 1024), [&](const auto& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) mask[k] = is_prescribed(grid, colliders, k, t);
  });
  return mask;
}

template std::optional<mpm::Mat<2>> slip_directions(const mpm::geometry::ColliderSet<2>&, const mpm::Vec<2>&, double);
template std::optional<mpm::Mat<3>> slip_directions(const mpm::geometry::ColliderSet<3>&, const mpm::Vec<3>&, double);
template bool is_prescribed(const mpm::SparseGrid<2>&, const mpm::geometry::ColliderSet<2>&, std::size_t, double);
template bool is_prescribed(const mpm::SparseGrid<3>&, const mpm::geometry::ColliderSet<3>&, std::size_t, double);
template std::vector<std::uint8_t> prescribed_nodes(const mpm::SparseGrid<2>&, const mpm::geometry::ColliderSet<2>&,
                                                    double);
template std::vector<std::uint8_t> prescribed_nodes(const mpm::SparseGrid<3>&, const mpm::geometry::ColliderSet<3>&,
                                                    double);

}  // namespace fluid::stages
