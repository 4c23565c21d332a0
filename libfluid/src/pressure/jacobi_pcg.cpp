#include <fluid/pressure/jacobi_pcg.h>
#include <fluid/pressure/pcg.h>

#include "cell_kernels.h"
#include "fluid_cells.h"

#include <chrono>

namespace fluid {

template <int dim>
SolveResult JacobiPcgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b,
                                        std::vector<double>& p, const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> inverse_diagonal, scratch;
  op.diagonal(inverse_diagonal);
  // A zero diagonal (a fluid cell whose corners all have beta = 0) has a zero row: leave it out.
  for (double& d : inverse_diagonal) d = d > 0.0 ? 1.0 / d : 0.0;
  detail::prepare_guess(op, p);
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  SolveResult result = pcg(
      [&](const std::vector<double>& x, std::vector<double>& y) { detail::apply_operator(op, x, y, scratch); },
      [&](const std::vector<double>& r, std::vector<double>& z) {
        for (std::size_t i = 0; i < r.size(); ++i) z[i] = inverse_diagonal[i] * r[i];
      },
      detail::fluid_rhs(op, b), p, control);
  result.setup_seconds = setup;
  return result;
}

template class JacobiPcgSolver<2>;
template class JacobiPcgSolver<3>;

}  // namespace fluid
