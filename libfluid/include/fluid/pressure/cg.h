#pragma once
//! Plain conjugate gradients (M = I): the baseline every preconditioner is measured against.
#include <fluid/pressure/pressure_solver.h>

namespace fluid {

template <int dim>
class CgSolver final : public PressureSolver<dim> {
public:
  std::string name() const override { return "cg"; }
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;
};

}  // namespace fluid
