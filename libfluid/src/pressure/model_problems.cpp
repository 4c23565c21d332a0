#include <fluid/pressure/model_problems.h>

#include <cmath>
#include <numbers>
#include <random>

namespace fluid {

namespace {
template <int dim>
CellOperator<dim> box(int n, OperatorKind<dim> kind) {
  CellOperator<dim> op;
  op.kind = kind;
  op.cells = IVec<dim>::Constant(n);
  op.dx = 1.0 / n;
  op.type.assign(static_cast<std::size_t>(op.cell_count()), CellType::fluid);
  op.beta.assign(static_cast<std::size_t>(op.node_count()), 0.0);
  IVec<dim> q = IVec<dim>::Zero();
  for (std::int64_t i = 0; i < op.node_count(); ++i) {
    const bool wall = (q.array() == 0).any() || (q.array() == n).any();
    double variation = 1.0;
    for (int a = 0; a < dim; ++a) variation *= std::sin(std::numbers::pi * (a + 1) * q[a] * op.dx);
    if (!wall) op.beta[i] = 1e-6 * (2.0 + variation);
    for (int a = 0; a < dim; ++a) {
      if (++q[a] <= n) break;
      q[a] = 0;
    }
  }
  return op;
}
}  // namespace

template <int dim>
CellOperator<dim> closed_box_problem(int n, OperatorKind<dim> kind) {
  return box<dim>(n, kind);
}

template <int dim>
CellOperator<dim> dam_break_problem(int n, OperatorKind<dim> kind) {
  CellOperator<dim> op = box<dim>(n, kind);
  IVec<dim> c = IVec<dim>::Zero();
  for (std::int64_t i = 0; i < op.cell_count(); ++i) {
    const bool water = 2 * c[0] < n && 2 * c[dim - 1] < n;
    if (!water) op.type[i] = CellType::empty;
    for (int a = 0; a < dim; ++a) {
      if (++c[a] < n) break;
      c[a] = 0;
    }
  }
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
  }
  return u;
}

template CellOperator<2> dam_break_problem<2>(int, OperatorKind<2>);
template CellOperator<3> dam_break_problem<3>(int, OperatorKind<3>);
template CellOperator<2> closed_box_problem<2>(int, OperatorKind<2>);
template CellOperator<3> closed_box_problem<3>(int, OperatorKind<3>);
template std::vector<Vec<2>> wall_consistent_velocity<2>(const CellOperator<2>&, unsigned);
template std::vector<Vec<3>> wall_consistent_velocity<3>(const CellOperator<3>&, unsigned);

}  // namespace fluid
