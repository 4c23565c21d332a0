#include <fluid/pressure/mgpcg.h>
#include <fluid/pressure/pcg.h>

#include "cell_kernels.h"
#include "fluid_cells.h"

#include <chrono>

namespace fluid {

template <int dim>
SolveResult MgpcgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b,
                                    std::vector<double>& p, const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> rhs;
  SolveResult result;
  if (detail::begin_solve(op, b, p, rhs, result)) return result;
  Multigrid<dim> multigrid(op, options_);
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<double> scratch;
  result = pcg(
      [&](const std::vector<double>& x, std::vector<double>& y) { detail::apply_operator(op, x, y, scratch); },
      [&](const std::vector<double>& r, std::vector<double>& z) { multigrid.apply(r, z); },
      rhs, p, control);
  result.setup_seconds = setup;
  return result;
}

template class MgpcgSolver<2>;
template class MgpcgSolver<3>;

}  // namespace fluid
