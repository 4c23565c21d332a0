#include <fluid/pressure/model_problems.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>

namespace fluid {

namespace {
template <int dim>
CellOperator<dim> box(int n, OperatorKind<dim> kind, const std::array<bool, dim>& periodic = {}) {
  CellOperator<dim> op;
  op.kind = kind;
  op.periodic = periodic;
  op.cells = IVec<dim>::Constant(n);
  op.dx = 1.0 / n;
  op.type.assign(static_cast<std::size_t>(op.cell_count()), CellType::fluid);
  op.beta.assign(static_cast<std::size_t>(op.node_count()), 0.0);
  const IVec<dim> extent = op.node_extent();
  IVec<dim> q = IVec<dim>::Zero();
  for (std::int64_t i = 0; i < op.node_count(); ++i) {
    bool wall = false;
    for (int a = 0; a < dim; ++a) wall = wall || (!periodic[a] && (q[a] == 0 || q[a] == n));
    double variation = 1.0;
    for (int a = 0; a < dim; ++a) variation *= std::sin(std::numbers::pi * (a + 1) * q[a] * op.dx);
    if (!wall) op.beta[i] = 1e-6 * (2.0 + variation);
    for (int a = 0; a < dim; ++a) {
      if (++q[a] < extent[a]) break;
      q[a] = 0;
    }
  }
  return op;
}

//! Empties the cells of `op` outside the water region x_0 < n/2 (when `column`) and x_last < n/2.
template <int dim>
void keep_water(CellOperator<dim>& op, int n, bool column) {
  IVec<dim> c = IVec<dim>::Zero();
  for (std::int64_t i = 0; i < op.cell_count(); ++i) {
    const bool water = (!column || 2 * c[0] < n) && 2 * c[dim - 1] < n;
    if (!water) op.type[i] = CellType::empty;
    for (int a = 0; a < dim; ++a) {
      if (++c[a] < n) break;
      c[a] = 0;
    }
  }
}
}  // namespace

template <int dim>
CellOperator<dim> closed_box_problem(int n, OperatorKind<dim> kind) {
  return box<dim>(n, kind);
}

template <int dim>
CellOperator<dim> dam_break_problem(int n, OperatorKind<dim> kind) {
  CellOperator<dim> op = box<dim>(n, kind);
  keep_water(op, n, true);
  return op;
}

template <int dim>
CellOperator<dim> periodic_box_problem(int n, OperatorKind<dim> kind) {
  std::array<bool, dim> periodic;
  periodic.fill(true);
  return box<dim>(n, kind, periodic);
}

template <int dim>
CellOperator<dim> periodic_channel_problem(int n, OperatorKind<dim> kind) {
  std::array<bool, dim> periodic{};
  periodic[0] = true;
  CellOperator<dim> op = box<dim>(n, kind, periodic);
  keep_water(op, n, false);
  return op;
}

template <int dim>
CellOperator<dim> pile_channel_problem(int n) {
  CellOperator<dim> op = periodic_channel_problem<dim>(n, OperatorKind<dim>::node_cell);
  constexpr double radius = 0.2;
  const IVec<dim> extent = op.node_extent();
  IVec<dim> q = IVec<dim>::Zero();
  for (std::int64_t i = 0; i < op.node_count(); ++i) {
    Vec<dim> from_axis = q.template cast<double>() * op.dx - Vec<dim>::Constant(0.5);
    from_axis[dim - 1] = 0.0;
    const double distance = from_axis.norm();
    if (distance < radius) {
      if (distance > radius - op.dx && distance > 0.0)
        op.set_slip(i, Mat<dim>::Identity() - from_axis * from_axis.transpose() / (distance * distance));
      else
        op.beta[static_cast<std::size_t>(i)] = 0.0;
    }
    for (int a = 0; a < dim; ++a) {
      if (++q[a] < extent[a]) break;
      q[a] = 0;
    }
  }
  op.empty_cells_without_unknowns();
  return op;
}

template <int dim>
std::vector<Vec<dim>> wall_consistent_velocity(const CellOperator<dim>& op, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<Vec<dim>> u(static_cast<std::size_t>(op.node_count()));
  for (std::size_t i = 0; i < u.size(); ++i) {
    for (int a = 0; a < dim; ++a) u[i][a] = uniform(rng);
    if (op.beta[i] == 0.0) u[i].setZero();
    u[i] = op.free_directions(static_cast<std::int64_t>(i)) * u[i];
  }
  return u;
}

template CellOperator<2> dam_break_problem<2>(int, OperatorKind<2>);
template CellOperator<3> dam_break_problem<3>(int, OperatorKind<3>);
template CellOperator<2> periodic_box_problem<2>(int, OperatorKind<2>);
template CellOperator<3> periodic_box_problem<3>(int, OperatorKind<3>);
template CellOperator<2> periodic_channel_problem<2>(int, OperatorKind<2>);
template CellOperator<3> periodic_channel_problem<3>(int, OperatorKind<3>);
template CellOperator<2> pile_channel_problem<2>(int);
template CellOperator<3> pile_channel_problem<3>(int);
template CellOperator<2> closed_box_problem<2>(int, OperatorKind<2>);
template CellOperator<3> closed_box_problem<3>(int, OperatorKind<3>);
template std::vector<Vec<2>> wall_consistent_velocity<2>(const CellOperator<2>&, unsigned);
template std::vector<Vec<3>> wall_consistent_velocity<3>(const CellOperator<3>&, unsigned);

}  // namespace fluid
