#pragma once
//! hypre Struct interface: PCG preconditioned by one PFMG V-cycle (semicoarsening geometric multigrid,
//! Galerkin coarse operators). Poisson uses the 2*dim+1-point stencil and red-black Gauss-Seidel;
//! NodeCell the full 3^dim-point stencil and weighted Jacobi. Empty cells are identity rows with zero
//! right-hand side, so the box stays one Struct box.
#include <fluid/pressure/pressure_solver.h>

namespace fluid {

template <int dim>
class HyprePfmgSolver final : public PressureSolver<dim> {
public:
  std::string name() const override { return "hypre_pfmg"; }
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;
};

}  // namespace fluid
