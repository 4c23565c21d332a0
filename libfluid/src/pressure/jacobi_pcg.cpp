#include <fluid/pressure/jacobi_pcg.h>

#include <mpm/core/solve/conjugate_gradient.h>
#include <mpm/core/solve/preconditioners.h>

#include "fluid_cells.h"

#include <chrono>

namespace fluid {

template <int dim>
SolveResult JacobiPcgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b,
                                        std::vector<double>& p, const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  // A zero diagonal (a fluid cell whose corners all have beta = 0) has a zero row: the
  // preconditioner leaves it out.
  std::vector<double> diagonal;
  op.diagonal(diagonal);
  const mpm::solve::JacobiPreconditioner jacobi(std::move(diagonal));
  detail::prepare_guess(op, p);
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  SolveResult result =
      mpm::solve::conjugate_gradient(detail::OperatorProduct<dim>(op), jacobi, detail::fluid_rhs(op, b), p, control);
  result.setup_seconds = setup;
  return result;
}

template class JacobiPcgSolver<2>;
template class JacobiPcgSolver<3>;

}  // namespace fluid
