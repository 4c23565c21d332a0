#pragma once
//! Conjugate gradients preconditioned by the inverse diagonal of A (Jacobi).
#include <fluid/pressure/pressure_solver.h>

namespace fluid {

template <int dim>
class JacobiPcgSolver final : public PressureSolver<dim> {
public:
  std::string name() const override { return "jacobi_pcg"; }
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;
};

}  // namespace fluid
