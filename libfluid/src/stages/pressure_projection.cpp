// Pressure projection on the semi-staggered grid (Gao et al. 2018,
// mixture constraint of Anderson & Jackson 1967). Preconditions: grid velocities after the
// explicit update (and viscosity) with the wall/collider conditions applied; particles inside
// the grid. In order:
//   1. fluid cells: c is fluid iff it holds a particle, c = floor((x_p - origin) / dx), and
//      at least one of its corners is free (below); the operator box is the bounding box of
//      the cells holding particles (every other cell: p = 0), and the whole period on a
//      periodic axis of the grid, where the operator wraps (its nodes are the canonical ones;
//      stage periodic_fill hands their velocities to the ghosts);
//   2. per node i of the box: u_i = n_w v_i^* + n_s v_{s,i}^*  (n_w = 1, n_s = 0 single phase),
//      beta_i = dt (n_w / rho_w + n_s / rho_s) for nodes with mass that no obstacle prescribes,
//      beta_i = 0 on nodes an obstacle holds (sticky) and u_i = v_i^*, their boundary velocity
//      (wall normals are exact Neumann conditions on p); on a node slipping along obstacles,
//      with P the projector onto the directions they leave free, (I - P) u_i = (I - P) v_i^*
//      and the mobility beta_i P / phi_i (cell_operator.h, phi_i the node's open share,
//      open_share()): the pressure moves the tangential velocity, so that slip walls conserve
//      mass and hold water at rest too. With
//      the grains' flux left out where the obstacles hold the mixture, b . z = 0 for every
//      null vector z of A that static obstacles close off (a checkerboard on one layer of
//      cells across a 3D flume: (D^T z)_i vanishes except at held nodes, where u_i . (D^T z)_i
//      is then 0), so the solve stays consistent;
//   3. solve D B D^T p = -D u (cell_operator.h), initial guess the previous pressure, after
//      removing from b its components along the null vectors of A in the span of the
//      constant and the checkerboards prod_{a in S} (-1)^{c_a}, |S| >= 2 (the Q1-P0 modes),
//      which exist in regions closed by walls (a full cavity) or periodic axes. A moving lid
//      drives the checkerboard, so without this b is not in the range of A. The same
//      components are removed from p after the solve: this fixes the pressure level
//      (null_space.h; zero mean over a fully periodic box). Besides the relative tolerance the
//      solve stops at the round-off level of D u (1e-14 sqrt(cells) 2 dim max|u| / dx);
//   4. v_i <- v_i^* + (dt / rho_w) (D^T p)_i = v_i^* - (dt / rho_w) (G p)_i, so that
//      D (n_w v_w + n_s v_s) = 0 in every fluid cell once the coupling applies the solid's part.
// A solve that misses its tolerance is retried by the fallback solver when the scene names one
// (pressure.fallback), then warns or stops (pressure.on_failure) with iterations and residual;
// it is never silent.
#include <fluid/pressure/null_space.h>
#include <fluid/stages/prescribed_nodes.h>
#include <fluid/stages/pressure_projection.h>

#include "fluid_cell.h"

#include <mpm/core/error.h>
#include <mpm/core/solve/vector_space.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

namespace fluid::stages {

template <int dim>
PressureProjection<dim>::PressureProjection(double density, mpm::geometry::ColliderSet<dim> colliders,
                                            PressureSettings settings, std::string name)
    : density_(density),
      colliders_(std::move(colliders)),
      settings_(std::move(settings)),
      name_(std::move(name)),
      solver_(make_pressure_solver<dim>(settings_.solver, settings_.setup_reuse)),
      fallback_(settings_.fallback.empty() ? nullptr
                                           : make_pressure_solver<dim>(settings_.fallback, settings_.setup_reuse)) {}

namespace {
//! Calls f(local coordinate, local index) for every point of a box with `n` points per axis
//! (x fastest, so the index counts the points in order).
template <int dim, class Fn>
void for_each_point(const IVec<dim>& n, Fn&& f) {
  std::int64_t i = 0;
  mpm::for_each_in_box<dim>(IVec<dim>::Zero(), n - IVec<dim>::Ones(), [&](const IVec<dim>& c) { f(c, i++); });
}

//! Makes `op` the node/cell operator box of the particles X (non-empty): the bounding box of
//! the cells holding a particle (the whole period along periodic axes), those cells fluid and
//! the others empty, no beta yet. Returns the grid cell of the box's cell (0, ...).
template <int dim>
IVec<dim> fluid_cell_box(const mpm::SparseGrid<dim>& g, const std::vector<Vec<dim>>& X, CellOperator<dim>& op) {
  IVec<dim> lo = fluid_cell_of(g, X[0]), hi = lo;
  for (const Vec<dim>& x : X) {
    const IVec<dim> c = fluid_cell_of(g, x);
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
  op.cells = hi - lo + IVec<dim>::Ones();
  op.type.assign(static_cast<std::size_t>(op.cell_count()), CellType::empty);
  for (const Vec<dim>& x : X) op.type[op.cell_index(fluid_cell_of(g, x) - lo)] = CellType::fluid;
  return lo;
}

//! The share of the 2^dim cells around the node at x (spacing dx) whose centres no obstacle
//! prescribes at time t: the part of the node's dual cell that the fluid can fill.
template <int dim>
double dual_cell_share(const mpm::geometry::ColliderSet<dim>& colliders, const Vec<dim>& x, double dx, double t) {
  int open = 0;
  for (int k = 0; k < (1 << dim); ++k) {
    Vec<dim> centre = x;
    for (int a = 0; a < dim; ++a) centre[a] += ((k >> a) & 1) ? 0.5 * dx : -0.5 * dx;
    open += !colliders.prescribes(centre, t);
  }
  return static_cast<double>(open) / (1 << dim);
}
}  // namespace

template <int dim>
void PressureProjection<dim>::run(mpm::MpmState<dim>& s) {
  mpm::SparseGrid<dim>& g = s.grid;
  const auto& X = s.particles.x;
  if (X.empty()) return;

  // 1. Fluid cells and their bounding box (the whole period along periodic axes).
  const IVec<dim> old_lo = box_lo_, old_cells = op_.cells;
  std::vector<double> old_p;
  old_p.swap(p_);
  const IVec<dim> lo = fluid_cell_box(g, X, op_);
  box_lo_ = lo;

  // 2. Node fields of the box.
  const std::vector<std::uint8_t> fixed = prescribed_nodes(g, colliders_, s.time + s.dt);
  const std::int64_t nodes = op_.node_count();
  op_.beta.assign(static_cast<std::size_t>(nodes), 0.0);
  u_.assign(static_cast<std::size_t>(nodes), Vec<dim>::Zero());
  std::vector<mpm::Index> storage(static_cast<std::size_t>(nodes), -1);
  const double fluid_beta = s.dt / density_;
  op_.clear_slip();
  open_share_.assign(static_cast<std::size_t>(nodes), 1.0);
  for_each_point<dim>(op_.node_extent(), [&](const IVec<dim>& n, std::int64_t i) {
    const mpm::Index k = g.node_index(lo + n);
    storage[i] = k;
    if (k < 0) return;
    const Vec<dim>& v = g.velocity[k];
    u_[i] = mixture_ ? mixture_->fluid_fraction[k] * v + mixture_->solid_flux[k] : v;
    if (g.mass[k] <= 0.0) return;
    const double beta =
        mixture_ ? s.dt * (mixture_->fluid_fraction[k] / density_ + mixture_->solid_mobility[k]) : fluid_beta;
    if (!fixed[k]) {
      op_.beta[i] = beta;
      return;
    }
    // A prescribed node: the components the obstacles hold are the fluid's (the obstacle's
    // velocity, not the grains' flux), so that D u has no part along the null vectors the
    // obstacles close off; along a slipping obstacle the pressure moves the rest.
    const std::optional<mpm::Mat<dim>> free = slip_directions(colliders_, g.node_position(k), s.time + s.dt);
    if (!free) {
      u_[i] = v;
      return;
    }
    u_[i] = *free * u_[i] + (mpm::Mat<dim>::Identity() - *free) * v;
    const double share = dual_cell_share(colliders_, g.node_position(k), g.dx(), s.time + s.dt);
    if (share > 0.0) open_share_[i] = share;
    op_.beta[i] = beta / open_share_[i];
    if (free->trace() < dim - 0.5) op_.set_slip(i, *free);
  });

  op_.empty_cells_without_unknowns();

  // 3. Solve, starting from the previous pressure where the boxes overlap.
  op_.divergence(u_, b_);
  const std::vector<std::vector<double>> null_space = null_space_basis(op_);
  remove_components(null_space, b_);
  p_.assign(static_cast<std::size_t>(op_.cell_count()), 0.0);
  for_each_point<dim>(op_.cells, [&](const IVec<dim>& c, std::int64_t i) {
    const IVec<dim> old = c + lo - old_lo;
    if (op_.type[i] != CellType::fluid || (old.array() < 0).any() || (old.array() >= old_cells.array()).any()) return;
    std::int64_t j = 0;
    for (int a = dim - 1; a >= 0; --a) j = j * old_cells[a] + old[a];
    p_[i] = old_p[j];
  });
  // A discretely divergence-free u leaves b at round-off, which no relative tolerance can reach
  // (and whose parts along null vectors outside the candidates, as in 3D periodic boxes, are
  // inconsistent): the solve also stops at 1e-14 of the scale of the terms of D u.
  double speed = 0.0;
  for (const Vec<dim>& u : u_) speed = std::max(speed, u.cwiseAbs().maxCoeff());
  const double floor = 1e-14 * std::sqrt(static_cast<double>(op_.cell_count())) * 2.0 * dim * speed / g.dx();
  SolveControl control = settings_.control;
  control.absolute_tolerance = std::max(control.absolute_tolerance, floor);
  const PressureSolver<dim>* solved_by = solver_.get();
  const std::vector<double> guess = fallback_ ? p_ : std::vector<double>{};
  result_ = solver_->solve(op_, b_, p_, control);
  if (!result_.converged && fallback_) {
    std::cerr << "warning: " << failure(s, *solver_) << "; retrying with '" << fallback_->name() << "'\n";
    p_ = guess;
    result_ = fallback_->solve(op_, b_, p_, control);
    solved_by = fallback_.get();
  }
  remove_components(null_space, p_);
  // A tolerance below the floor (1e-30, or 1e-8 of a right-hand side a few digits above
  // round-off) is not met; the solve is as good as double precision allows, so it does not
  // count as failed, but the run says so once and diagnostics.csv flags every such solve. A
  // right-hand side at round-off itself (u already divergence-free) needs no solve at all.
  const double rtol = settings_.control.relative_tolerance, b_norm = std::sqrt(mpm::solve::dot(b_, b_));
  stopped_at_round_off_ = result_.converged && result_.relative_residual > rtol && b_norm > floor &&
                          floor > std::max(rtol * b_norm, settings_.control.absolute_tolerance);
  if (stopped_at_round_off_ && !round_off_reported_) {
    round_off_reported_ = true;
    std::cerr << "warning: stage '" << name() << "': the pressure tolerance " << rtol
              << " is below round-off for this system: the solve stopped at its floor (1e-14 of the scale of D u)"
              << " with relative residual " << result_.relative_residual << " at t = " << s.time << " s, step "
              << s.step << "; said once per run, diagnostics.csv flags every such solve (pressure_round_off = 1)\n";
  }
  if (!result_.converged) {
    ++unconverged_;
    if (settings_.on_failure == OnFailure::stop) throw mpm::NumericalError(failure(s, *solved_by));
    std::cerr << "warning: " << failure(s, *solved_by) << "\n";
  }

  // 4. v_w += (dt / (rho_w phi)) P D^T p: the impulse (beta / phi) P D^T p rescaled from the
  // mixture beta (open_share()).
  std::vector<Vec<dim>> impulse(static_cast<std::size_t>(nodes), Vec<dim>::Zero());
  op_.subtract_gradient(p_, impulse);
  for (std::int64_t i = 0; i < nodes; ++i)
    if (op_.beta[i] > 0.0) g.velocity[storage[i]] += (fluid_beta / (op_.beta[i] * open_share_[i])) * impulse[i];
}

template <int dim>
std::string PressureProjection<dim>::failure(const mpm::MpmState<dim>& s, const PressureSolver<dim>& solver) const {
  std::ostringstream why;
  why << "stage '" << name() << "': pressure solver '" << solver.name() << "' did not converge in "
      << result_.iterations << " iterations (relative residual " << result_.relative_residual << ", tolerance "
      << settings_.control.relative_tolerance << ") at t = " << s.time << " s, step " << s.step;
  return why.str();
}

template <int dim>
double PressureProjection<dim>::pressure_at(const mpm::SparseGrid<dim>& grid, const Vec<dim>& x) const {
  const IVec<dim> c = fluid_cell_of(grid, x) - box_lo_;
  if ((c.array() < 0).any() || (c.array() >= op_.cells.array()).any()) return 0.0;
  const std::int64_t i = op_.cell_index(c);
  return op_.type[i] == CellType::fluid ? p_[i] : 0.0;
}

template class PressureProjection<2>;
template class PressureProjection<3>;

}  // namespace fluid::stages
