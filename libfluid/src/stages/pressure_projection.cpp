// Pressure projection on the semi-staggered grid (DESIGN.md "LANS fluid"; Gao et al. 2018,
// mixture constraint of Anderson & Jackson 1967). Preconditions: grid velocities after the
// explicit update (and viscosity) with the wall/collider conditions applied; particles inside
// the grid. In order:
//   1. fluid cells: c is fluid iff it holds a particle, c = floor((x_p - origin) / dx), and
//      at least one of its corners is free (below); the operator box is the bounding box of
//      the cells holding particles (every other cell: p = 0);
//   2. per node i of the box: u_i = n_w v_i^* + n_s v_{s,i}^*  (n_w = 1, n_s = 0 single phase),
//      beta_i = dt (n_w / rho_w + n_s / rho_s) for nodes with mass that no obstacle prescribes,
//      beta_i = 0 otherwise (prescribed nodes keep their boundary velocity: wall normals are
//      exact Neumann conditions on p);
//   3. solve D B D^T p = -D u (cell_operator.h), initial guess the previous pressure, after
//      removing from b its components along the null vectors of A in the span of the
//      constant and the checkerboards prod_{a in S} (-1)^{c_a}, |S| >= 2 (the Q1-P0 modes),
//      which exist in regions closed by walls (a full cavity). A moving lid drives the
//      checkerboard, so without this b is not in the range of A;
//   4. v_i <- v_i^* + (dt / rho_w) (D^T p)_i = v_i^* - (dt / rho_w) (G p)_i, so that
//      D (n_w v_w + n_s v_s) = 0 in every fluid cell once the coupling applies the solid's part.
// A solve that misses its tolerance warns or stops (pressure.on_failure) with iterations and
// residual; it is never silent.
#include <fluid/stages/prescribed_nodes.h>
#include <fluid/stages/pressure_projection.h>

#include <mpm/core/error.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <bit>
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

//! b minus its projection on the null space of A within the span V of the constant and the
//! checkerboards (on the fluid cells): the null vectors V alpha solve (V^T A V) alpha = 0, as A
//! is positive semi-definite. Combinations matter: one emptied cell of a closed cavity leaves
//! the constant of the other checkerboard colour in the null space.
template <int dim>
void make_consistent(const CellOperator<dim>& op, std::vector<double>& b) {
  std::vector<std::vector<double>> V;
  for (int S = 0; S < (1 << dim); ++S) {
    if (std::popcount(static_cast<unsigned>(S)) == 1) continue;
    std::vector<double> v(b.size(), 0.0);
    for_each_point<dim>(op.cells, [&](const IVec<dim>& c, std::int64_t i) {
      if (op.type[i] != CellType::fluid) return;
      int parity = 0;
      for (int a = 0; a < dim; ++a) parity += ((S >> a) & 1) * c[a];
      v[i] = parity % 2 ? -1.0 : 1.0;
    });
    V.push_back(std::move(v));
  }
  const int m = static_cast<int>(V.size());
  auto dot = [](const std::vector<double>& x, const std::vector<double>& y) {
    double d = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) d += x[i] * y[i];
    return d;
  };
  Eigen::MatrixXd G(m, m), N(m, m);  // V^T A V and V^T V
  std::vector<double> Av;
  for (int j = 0; j < m; ++j) {
    op.apply(V[j], Av);
    for (int i = 0; i < m; ++i) {
      G(i, j) = dot(V[i], Av);
      N(i, j) = dot(V[i], V[j]);
    }
  }
  // Generalised eigenproblem G alpha = lambda N alpha (N: the candidates' Gram matrix, SPD
  // while the fluid cells are not all of one colour; a tiny ridge keeps it so).
  N += 1e-12 * N.trace() * Eigen::MatrixXd::Identity(m, m);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(G, N);
  const double largest = eig.eigenvalues().cwiseAbs().maxCoeff();
  std::vector<std::vector<double>> basis;
  for (int k = 0; k < m; ++k) {
    if (std::abs(eig.eigenvalues()[k]) > 1e-10 * largest && largest > 0.0) continue;
    std::vector<double> v(b.size(), 0.0);
    for (int j = 0; j < m; ++j)
      for (std::size_t i = 0; i < v.size(); ++i) v[i] += eig.eigenvectors()(j, k) * V[j][i];
    for (const auto& q : basis) {
      const double vq = dot(v, q);
      for (std::size_t i = 0; i < v.size(); ++i) v[i] -= vq * q[i];
    }
    const double norm = std::sqrt(dot(v, v));
    if (norm <= 1e-8) continue;
    for (double& x : v) x /= norm;
    basis.push_back(std::move(v));
  }
  for (const auto& q : basis) {
    const double bq = dot(b, q);
    for (std::size_t i = 0; i < b.size(); ++i) b[i] -= bq * q[i];
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
    u_[i] = mixture_ ? mixture_->fluid_fraction[k] * g.velocity[k] + mixture_->solid_flux[k] : g.velocity[k];
    if (g.mass[k] <= 0.0 || fixed[k]) return;
    op_.beta[i] = mixture_ ? s.dt * (mixture_->fluid_fraction[k] / density_ + mixture_->solid_mobility[k])
                           : fluid_beta;
  });

  // A fluid cell whose corners are all prescribed (a particle inside a wall) has no pressure
  // unknown that could change its divergence: it is left out (p = 0) instead of making the
  // system inconsistent.
  for_each_point<dim>(op_.cells, [&](const IVec<dim>& c, std::int64_t ci) {
    if (op_.type[ci] != CellType::fluid) return;
    for (int k = 0; k < (1 << dim); ++k) {
      IVec<dim> n = c;
      for (int a = 0; a < dim; ++a) n[a] += (k >> a) & 1;
      if (op_.beta[op_.node_index(n)] > 0.0) return;
    }
    op_.type[ci] = CellType::empty;
  });

  // 3. Solve, starting from the previous pressure where the boxes overlap.
  op_.divergence(u_, b_);
  make_consistent(op_, b_);
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
