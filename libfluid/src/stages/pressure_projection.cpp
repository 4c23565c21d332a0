// Pressure projection on the semi-staggered grid (DESIGN.md "LANS fluid"; Gao et al. 2018,
// mixture constraint of Anderson & Jackson 1967). Preconditions: grid velocities after the
// explicit update (and viscosity) with the wall/collider conditions applied; particles inside
// the grid. In order:
//   1. fluid cells: c is fluid iff it holds a particle, c = floor((x_p - origin) / dx); the
//      operator box is the bounding box of the fluid cells (every other cell: p = 0);
//   2. per node i of the box: u_i = n_w v_i^* + n_s v_{s,i}^*  (n_w = 1, n_s = 0 single phase),
//      beta_i = dt (n_w / rho_w + n_s / rho_s) for nodes with mass that no obstacle prescribes,
//      beta_i = 0 otherwise (prescribed nodes keep their boundary velocity: wall normals are
//      exact Neumann conditions on p);
//   3. solve D B D^T p = -D u (cell_operator.h), initial guess the previous pressure;
//   4. v_i <- v_i^* + (dt / rho_w) (D^T p)_i = v_i^* - (dt / rho_w) (G p)_i, so that
//      D (n_w v_w + n_s v_s) = 0 in every fluid cell once the coupling applies the solid's part.
// A solve that misses its tolerance warns or stops (pressure.on_failure) with iterations and
// residual; it is never silent.
#include <fluid/stages/prescribed_nodes.h>
#include <fluid/stages/pressure_projection.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

namespace fluid::stages {

template <int dim>
PressureProjection<dim>::PressureProjection(double density, mpm::geometry::ColliderSet<dim> colliders,
                                            PressureSettings settings)
    : density_(density),
      colliders_(std::move(colliders)),
      settings_(std::move(settings)),
      solver_(make_pressure_solver<dim>(settings_.solver)) {}

namespace {
template <int dim>
IVec<dim> cell_of(const mpm::SparseGrid<dim>& g, const Vec<dim>& x) {
  IVec<dim> c;
  for (int a = 0; a < dim; ++a)
    c[a] = std::clamp(static_cast<int>(std::floor((x[a] - g.origin()[a]) / g.dx())), 0, g.node_counts()[a] - 2);
  return c;
}

//! Calls f(local coordinate, local index) for every point of a box with `n` points per axis.
template <int dim, class Fn>
void for_each_point(const IVec<dim>& n, Fn&& f) {
  IVec<dim> c = IVec<dim>::Zero();
  const std::int64_t count = n.template cast<std::int64_t>().prod();
  for (std::int64_t i = 0; i < count; ++i) {
    f(c, i);
    for (int a = 0; a < dim; ++a) {
      if (++c[a] < n[a]) break;
      c[a] = 0;
    }
  }
}
}  // namespace

template <int dim>
void PressureProjection<dim>::run(mpm::MpmState<dim>& s) {
  mpm::SparseGrid<dim>& g = s.grid;
  const auto& X = s.particles.x;
  if (X.empty()) return;

  // 1. Fluid cells and their bounding box.
  IVec<dim> lo = cell_of(g, X[0]), hi = lo;
  for (const Vec<dim>& x : X) {
    const IVec<dim> c = cell_of(g, x);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  const IVec<dim> old_lo = box_lo_, old_cells = op_.cells;
  std::vector<double> old_p;
  old_p.swap(p_);
  op_.kind = CellOperator<dim>::Kind::node_cell;
  op_.dx = g.dx();
  op_.cells = hi - lo + IVec<dim>::Ones();
  box_lo_ = lo;
  op_.type.assign(static_cast<std::size_t>(op_.cell_count()), CellType::empty);
  for (const Vec<dim>& x : X) op_.type[op_.cell_index(cell_of(g, x) - lo)] = CellType::fluid;

  // 2. Node fields of the box.
  const std::vector<std::uint8_t> fixed = prescribed_nodes(g, colliders_, s.time + s.dt);
  const std::int64_t nodes = op_.node_count();
  op_.beta.assign(static_cast<std::size_t>(nodes), 0.0);
  u_.assign(static_cast<std::size_t>(nodes), Vec<dim>::Zero());
  std::vector<mpm::Index> storage(static_cast<std::size_t>(nodes), -1);
  const double fluid_beta = s.dt / density_;
  for_each_point<dim>(op_.cells + IVec<dim>::Ones(), [&](const IVec<dim>& n, std::int64_t i) {
    const mpm::Index k = g.node_index(lo + n);
    storage[i] = k;
    if (k < 0) return;
    u_[i] = g.velocity[k];
    if (g.mass[k] <= 0.0 || fixed[k]) return;
    op_.beta[i] = fluid_beta;
    if (mixture_) {
      const double nw = mixture_->fluid_fraction[k];
      u_[i] = nw * g.velocity[k] + mixture_->solid_flux[k];
      op_.beta[i] = s.dt * (nw / density_ + mixture_->solid_mobility[k]);
    }
  });

  // 3. Solve, starting from the previous pressure where the boxes overlap.
  op_.divergence(u_, b_);
  p_.assign(static_cast<std::size_t>(op_.cell_count()), 0.0);
  for_each_point<dim>(op_.cells, [&](const IVec<dim>& c, std::int64_t i) {
    const IVec<dim> old = c + lo - old_lo;
    if (op_.type[i] != CellType::fluid || (old.array() < 0).any() || (old.array() >= old_cells.array()).any()) return;
    std::int64_t j = 0;
    for (int a = dim - 1; a >= 0; --a) j = j * old_cells[a] + old[a];
    p_[i] = old_p[j];
  });
  result_ = solver_->solve(op_, b_, p_, settings_.control);
  if (!result_.converged) {
    std::ostringstream why;
    why << "stage '" << name() << "': pressure solver '" << solver_->name() << "' did not converge in "
        << result_.iterations << " iterations (relative residual " << result_.relative_residual << ", tolerance "
        << settings_.control.relative_tolerance << ") at t = " << s.time << " s, step " << s.step;
    if (settings_.on_failure == OnFailure::stop) throw mpm::NumericalError(why.str());
    std::cerr << "warning: " << why.str() << "\n";
  }

  // 4. v_w += (dt / rho_w) D^T p: the impulse beta D^T p rescaled from the mixture beta.
  std::vector<Vec<dim>> impulse(static_cast<std::size_t>(nodes), Vec<dim>::Zero());
  op_.subtract_gradient(p_, impulse);
  for (std::int64_t i = 0; i < nodes; ++i)
    if (op_.beta[i] > 0.0) g.velocity[storage[i]] += (fluid_beta / op_.beta[i]) * impulse[i];
}

template <int dim>
double PressureProjection<dim>::pressure_at(const mpm::SparseGrid<dim>& grid, const Vec<dim>& x) const {
  const IVec<dim> c = cell_of(grid, x) - box_lo_;
  if ((c.array() < 0).any() || (c.array() >= op_.cells.array()).any()) return 0.0;
  const std::int64_t i = op_.cell_index(c);
  return op_.type[i] == CellType::fluid ? p_[i] : 0.0;
}

template class PressureProjection<2>;
template class PressureProjection<3>;

}  // namespace fluid::stages
