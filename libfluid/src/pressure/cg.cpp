#include <fluid/pressure/cg.h>
#include <fluid/pressure/pcg.h>

#include "cell_kernels.h"
#include "fluid_cells.h"

namespace fluid {

template <int dim>
SolveResult CgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                                 const SolveControl& control) {
  std::vector<double> scratch;
  detail::prepare_guess(op, p);
  return pcg([&](const std::vector<double>& x, std::vector<double>& y) { detail::apply_operator(op, x, y, scratch); },
             LinearMap{}, detail::fluid_rhs(op, b), p, control);
}

template class CgSolver<2>;
template class CgSolver<3>;

}  // namespace fluid
