#pragma once
//! Sparse direct back-end (SuiteSparse CHOLMOD, supernodal Cholesky) for verification on small
//! grids. A is assembled over the fluid cells (CellOperator::for_each_entry).
//! Regularisation: the NodeCell operator of a closed box is singular (constants and
//! checkerboard modes). CHOLMOD factors A + eps I with eps = 1e-12 max(diag A) and the solve
//! runs iterative refinement p += (A + eps I)^-1 (b - A p) until the residual meets the
//! control. For b in range(A) the null-space part of every correction is zero, and a range
//! component with eigenvalue lambda is reduced by eps / (lambda + eps) per step, so a few steps
//! reach round-off; `iterations` reports the refinement steps.
#include <fluid/pressure/pressure_solver.h>

namespace fluid {

template <int dim>
class CholmodSolver final : public PressureSolver<dim> {
public:
  std::string name() const override { return "cholmod"; }
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;
};

}  // namespace fluid
