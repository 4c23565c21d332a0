#pragma once
//! The default back-end: conjugate gradients preconditioned by one symmetric multigrid cycle
//! per iteration: the matrix-free geometric V-cycle of multigrid.h where it applies (Poisson,
//! 2D NodeCell), else the modulated Galerkin hierarchy of modulated_multigrid.h (3D NodeCell).
#include <fluid/pressure/multigrid.h>
#include <fluid/pressure/pressure_solver.h>

namespace fluid {

template <int dim>
class MgpcgSolver final : public PressureSolver<dim> {
public:
  MgpcgSolver() = default;
  explicit MgpcgSolver(const typename Multigrid<dim>::Options& options) : options_(options) {}
  std::string name() const override { return "mgpcg"; }
  //! Rebuilds the hierarchy for `op` (the operator changes every step) and runs PCG.
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;

private:
  typename Multigrid<dim>::Options options_;
};

}  // namespace fluid
