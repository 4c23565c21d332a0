#include <fluid/pressure/mgpcg.h>
#include <fluid/pressure/modulated_multigrid.h>

#include <mpm/core/solve/conjugate_gradient.h>

#include "fluid_cells.h"

#include <chrono>

namespace fluid {

namespace {
//! PCG preconditioned by `multigrid`; the time since `start` is the set-up.
template <int dim, class Preconditioner>
SolveResult solve_with(const CellOperator<dim>& op, const std::vector<double>& rhs, std::vector<double>& p,
                       const SolveControl& control, std::chrono::steady_clock::time_point start,
                       Preconditioner& multigrid) {
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  SolveResult result = mpm::solve::conjugate_gradient(detail::OperatorProduct<dim>(op), multigrid, rhs, p, control);
  result.setup_seconds = setup;
  return result;
}
}  // namespace

template <int dim>
SolveResult MgpcgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                                    const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> rhs;
  SolveResult result;
  if (detail::begin_solve(op, b, p, rhs, result)) return result;
  // 3D NodeCell: near-null modes that no smooth coarse space holds (modulated_multigrid.h).
  if (!Multigrid<dim>::supports(op)) {
    ModulatedMultigrid<dim> multigrid(op);
    return solve_with(op, rhs, p, control, start, multigrid);
  }
  Multigrid<dim> multigrid(op, options_);
  return solve_with(op, rhs, p, control, start, multigrid);
}

template class MgpcgSolver<2>;
template class MgpcgSolver<3>;

}  // namespace fluid
