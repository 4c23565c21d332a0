#pragma once
//! The default back-end: conjugate gradients preconditioned by one symmetric multigrid cycle
//! per iteration: the matrix-free geometric V-cycle of multigrid.h where it applies (Poisson,
//! 2D NodeCell), else the modulated Galerkin hierarchy of modulated_multigrid.h (3D NodeCell).
#include <fluid/pressure/multigrid.h>
#include <fluid/pressure/pressure_solver.h>

#include <memory>

namespace fluid {

template <int dim>
class ModulatedMultigrid;

//! Set-up reuse (3D NodeCell). The Galerkin hierarchy costs about as much as a solve, and from
//! one step to the next the operator often keeps its fluid cells and changes its coefficients
//! only (the mixture's fractions, the fluid's density at the nodes). Up to `setup_reuse`
//! solves share one hierarchy: each takes the new fine matrix and keeps the coarse spaces
//! (ModulatedMultigrid::refresh: the preconditioner stays symmetric positive definite, so CG
//! converges to the same tolerance), and a new hierarchy is built when refresh cannot keep the
//! coarse spaces (the fluid cells moved beyond them), when a solve took more than 1.5 times
//! (+ 2) the iterations of the solve that built it, or at forget() (the frame ends, where
//! restarts begin: a restarted run solves as the continuous one, bit for bit). A solve that a
//! kept hierarchy does not bring to the tolerance is done again, from the same initial guess,
//! with a new one (the iterations reported count both).
template <int dim>
class MgpcgSolver final : public PressureSolver<dim> {
public:
  explicit MgpcgSolver(int setup_reuse = 1);
  MgpcgSolver(const typename Multigrid<dim>::Options& options, int setup_reuse = 1);
  ~MgpcgSolver() override;
  std::string name() const override { return "mgpcg"; }
  //! Builds (or, see above, refreshes) the hierarchy for `op` and runs PCG.
  SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                    const SolveControl& control) override;
  void forget() override;

private:
  typename Multigrid<dim>::Options options_;
  int setup_reuse_ = 1;
  std::unique_ptr<ModulatedMultigrid<dim>> kept_;  //!< the hierarchy the next solve may refresh
  int served_ = 0;                                 //!< solves it has served
  int built_iterations_ = 0, last_iterations_ = 0;
};

}  // namespace fluid
