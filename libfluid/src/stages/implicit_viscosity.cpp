// Implicit viscous diffusion of the node velocities (LANS momentum, the n_w tau_w term with
// n_w = 1 and tau_w = mu (grad v + grad v^T), whose divergence is mu L v for div v = 0):
//   (v_i - dt nu (L v)_i) = v_i^*     for every node i with mass that no obstacle prescribes,
//   (L v)_i = sum_{a, +-} (v_{i+-e_a} - v_i) / dx^2  over the neighbours j with mass:
//     neighbours without mass are skipped (zero normal stress at the free surface),
//     prescribed neighbours enter with their wall/collider velocity (Dirichlet, moved to the
//     right-hand side).
// The matrix I - dt nu L is symmetric positive definite (diagonally dominant, symmetric
// neighbour relation); one CG solve acts on all dim components at once (the operator is the
// same for each), by the project's CG (mpm/core/solve). Precondition: grid velocities after
// the explicit update.
#include <fluid/stages/implicit_viscosity.h>
#include <fluid/stages/prescribed_nodes.h>

#include <mpm/core/error.h>
#include <mpm/core/solve/conjugate_gradient.h>
#include <mpm/core/solve/preconditioners.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace fluid::stages {

template <int dim>
ImplicitViscosity<dim>::ImplicitViscosity(double kinematic_viscosity, mpm::geometry::ColliderSet<dim> colliders,
                                          SolveControl control)
    : nu_(kinematic_viscosity), colliders_(std::move(colliders)), control_(control) {}

template <int dim>
void ImplicitViscosity<dim>::run(mpm::MpmState<dim>& s) {
  mpm::SparseGrid<dim>& g = s.grid;
  const double t = s.time + s.dt;
  const double c = s.dt * nu_ / (g.dx() * g.dx());
  const std::vector<std::uint8_t> fixed = prescribed_nodes(g, colliders_, t);

  // Unknowns, their neighbour lists and the right-hand side.
  constexpr int nb = 2 * dim;
  std::vector<mpm::Index> unknown(g.node_storage(), -1);
  std::vector<std::size_t> node;
  // On a periodic grid the unknowns are the canonical nodes and neighbours wrap (the ghosts
  // get the result from stage periodic_fill).
  const bool periodic = g.is_periodic();
  for (std::size_t k = 0; k < g.node_storage(); ++k)
    if (g.mass[k] > 0.0 && !fixed[k] && (!periodic || g.periodic_image(g.node_coord(k)) == g.node_coord(k))) {
      unknown[k] = static_cast<mpm::Index>(node.size());
      node.push_back(k);
    }
  const std::size_t n = node.size();
  std::vector<std::array<mpm::Index, nb>> neighbour(n);
  std::vector<double> diagonal(n, 1.0);
  std::vector<Vec<dim>> b(n), x(n);
  for (std::size_t u = 0; u < n; ++u) {
    const std::size_t k = node[u];
    const IVec<dim> coord = g.node_coord(k);
    b[u] = x[u] = g.velocity[k];
    for (int j = 0; j < nb; ++j) {
      neighbour[u][j] = -1;
      IVec<dim> other = coord;
      other[j / 2] += j % 2 ? 1 : -1;
      other = g.periodic_image(other);
      const bool inside = (other.array() >= 0).all() && (other.array() < g.node_counts().array()).all();
      const mpm::Index m = inside ? g.node_index(other) : -1;
      if (m < 0 || g.mass[m] <= 0.0) continue;
      diagonal[u] += c;
      if (fixed[m]) {
        Vec<dim> wall = g.velocity[m];
        colliders_.project(g.node_position(m), t, wall);
        b[u] += c * wall;
      } else {
        neighbour[u][j] = unknown[m];
      }
    }
  }
  const auto apply = [&](const std::vector<Vec<dim>>& v, std::vector<Vec<dim>>& y) {
    for (std::size_t u = 0; u < n; ++u) {
      Vec<dim> r = diagonal[u] * v[u];
      for (const mpm::Index m : neighbour[u])
        if (m >= 0) r -= c * v[m];
      y[u] = r;
    }
  };

  // Jacobi-preconditioned CG from v^*.
  result_ = mpm::solve::conjugate_gradient(apply, mpm::solve::JacobiPreconditioner(diagonal), b, x, control_);
  if (!result_.converged) {
    std::ostringstream why;
    why << "stage '" << name() << "': viscous CG did not converge in " << result_.iterations
        << " iterations (relative residual " << result_.relative_residual << ") at t = " << s.time << " s, step "
        << s.step;
    throw mpm::NumericalError(why.str());
  }
  for (std::size_t u = 0; u < n; ++u) g.velocity[node[u]] = x[u];
}

template class ImplicitViscosity<2>;
template class ImplicitViscosity<3>;

}  // namespace fluid::stages
