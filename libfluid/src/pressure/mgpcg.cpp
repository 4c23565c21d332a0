#include <fluid/pressure/mgpcg.h>
#include <fluid/pressure/modulated_multigrid.h>
#include <fluid/pressure/pcg.h>

#include "cell_kernels.h"
#include "fluid_cells.h"

#include <chrono>

namespace fluid {

namespace {
//! PCG with the given preconditioner; the time since `start` is the set-up.
template <int dim>
SolveResult solve_with(const CellOperator<dim>& op, const std::vector<double>& rhs, std::vector<double>& p,
                       const SolveControl& control, std::chrono::steady_clock::time_point start,
                       const LinearMap& precondition) {
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<double> scratch;
  SolveResult result = pcg(
      [&](const std::vector<double>& x, std::vector<double>& y) { detail::apply_operator(op, x, y, scratch); },
      precondition, rhs, p, control);
  result.setup_seconds = setup;
  return result;
}
}  // namespace

template <int dim>
SolveResult MgpcgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b,
                                    std::vector<double>& p, const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> rhs;
  SolveResult result;
  if (detail::begin_solve(op, b, p, rhs, result)) return result;
  // 3D NodeCell: near-null modes that no smooth coarse space holds (modulated_multigrid.h).
  if (!Multigrid<dim>::supports(op)) {
    ModulatedMultigrid<dim> multigrid(op);
    return solve_with(op, rhs, p, control, start,
                      [&](const std::vector<double>& r, std::vector<double>& z) { multigrid.apply(r, z); });
  }
  Multigrid<dim> multigrid(op, options_);
  return solve_with(op, rhs, p, control, start,
                    [&](const std::vector<double>& r, std::vector<double>& z) { multigrid.apply(r, z); });
}

template class MgpcgSolver<2>;
template class MgpcgSolver<3>;

}  // namespace fluid
