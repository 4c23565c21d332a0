#include <fluid/pressure/mgpcg.h>
#include <fluid/pressure/modulated_multigrid.h>

#include <mpm/core/solve/conjugate_gradient.h>

#include "fluid_cells.h"

#include <mpm/core/error.h>

#include <algorithm>
#include <chrono>
#include <string>

namespace fluid {

namespace {
//! PCG preconditioned by `multigrid`; the time since `start` is the set-up.
template <int dim, class Preconditioner>
SolveResult solve_with(const CellOperator<dim>& op, const std::vector<double>& rhs, std::vector<double>& p,
                       const SolveControl& control, std::chrono::steady_clock::time_point start,
                       Preconditioner& multigrid) {
  const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  SolveResult result = mpm::solve::conjugate_gradient(detail::OperatorProduct<dim>(op), multigrid, rhs, p, control);
  result.setup_seconds = setup;
  return result;
}
}  // namespace

template <int dim>
MgpcgSolver<dim>::MgpcgSolver(int setup_reuse) : MgpcgSolver(typename Multigrid<dim>::Options{}, setup_reuse) {}

template <int dim>
MgpcgSolver<dim>::MgpcgSolver(const typename Multigrid<dim>::Options& options, int setup_reuse)
    : options_(options), setup_reuse_(setup_reuse) {
  mpm::verify<mpm::InputError>(setup_reuse >= 1,
                               "MGPCG set-up reuse " + std::to_string(setup_reuse) + ": expected >= 1 solves");
}

template <int dim>
MgpcgSolver<dim>::~MgpcgSolver() = default;

template <int dim>
void MgpcgSolver<dim>::forget() {
  kept_.reset();
  served_ = 0;
}

template <int dim>
SolveResult MgpcgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                                    const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<double> rhs;
  SolveResult result;
  if (detail::begin_solve(op, b, p, rhs, result)) return result;
  if (Multigrid<dim>::supports(op)) {
    // The V-cycle's smoother is written for a scalar mobility per node: it preconditions the
    // operator with slipping nodes by the one that lets those nodes move freely (still
    // symmetric positive definite, so CG stays valid; only the count of iterations can change).
    CellOperator<dim> scalar;
    if (op.has_slip()) {
      scalar = op;
      scalar.clear_slip();
    }
    Multigrid<dim> multigrid(op.has_slip() ? scalar : op, options_);
    return solve_with(op, rhs, p, control, start, multigrid);
  }
  // 3D NodeCell: near-null modes that no smooth coarse space holds (modulated_multigrid.h).
  const bool slowed = last_iterations_ > built_iterations_ + std::max(2, built_iterations_ / 2);
  bool refreshed = kept_ && served_ < setup_reuse_ && !slowed && kept_->refresh(op);
  const std::vector<double> guess = refreshed ? p : std::vector<double>{};
  if (!refreshed) {
    kept_ = std::make_unique<ModulatedMultigrid<dim>>(op);
    served_ = 0;
  }
  result = solve_with(op, rhs, p, control, start, *kept_);
  int spent = 0;                         // iterations of a kept hierarchy's failed try
  if (refreshed && !result.converged) {  // a kept hierarchy never fails a solve: built anew
    spent = result.iterations;
    p = guess;
    kept_ = std::make_unique<ModulatedMultigrid<dim>>(op);
    served_ = 0;
    refreshed = false;
    result = solve_with(op, rhs, p, control, std::chrono::steady_clock::now(), *kept_);
  }
  ++served_;
  last_iterations_ = result.iterations;
  if (!refreshed) built_iterations_ = result.iterations;
  result.iterations += spent;
  if (setup_reuse_ == 1) forget();  // nothing to keep: free the memory
  return result;
}

template class MgpcgSolver<2>;
template class MgpcgSolver<3>;

}  // namespace fluid
