#include <fluid/pressure/cg.h>

#include <mpm/core/solve/conjugate_gradient.h>
#include <mpm/core/solve/preconditioners.h>

#include "fluid_cells.h"

namespace fluid {

template <int dim>
SolveResult CgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                                 const SolveControl& control) {
  detail::prepare_guess(op, p);
  return mpm::solve::conjugate_gradient(detail::OperatorProduct<dim>(op), mpm::solve::IdentityPreconditioner{},
                                        detail::fluid_rhs(op, b), p, control);
}

template class CgSolver<2>;
template class CgSolver<3>;

}  // namespace fluid
