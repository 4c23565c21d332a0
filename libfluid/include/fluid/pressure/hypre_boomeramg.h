#pragma once
//! hypre IJ/ParCSR interface: PCG preconditioned by one BoomerAMG V-cycle (algebraic
//! multigrid, symmetric hybrid Gauss-Seidel), on the fluid cells only, for both operator kinds.
#include <fluid/pressure/pressure_solver.h>

namespace fluid {

template <int dim>
class HypreBoomerAmgSolver final : public PressureSolver<dim> {
public:
  std::string name() const override { return "hypre_boomeramg"; }
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;
};

}  // namespace fluid
