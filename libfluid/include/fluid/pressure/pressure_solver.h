#pragma once
//! One interface for every pressure solver back-end (after OpenVDB's ConjGradient State,
//! AMReX's bottom-solver enum). A solve never fails silently: it returns its result and the
//! caller (a scene setting) decides whether a non-converged solve warns or stops.
#include <fluid/pressure/cell_operator.h>

#include <mpm/core/solve/solve_control.h>

#include <memory>
#include <string>
#include <vector>

namespace fluid {

// The solve layer of the core (mpm/core/solve/): every back-end reports the same result.
using mpm::solve::SolveControl;
using mpm::solve::SolveResult;

template <int dim>
class PressureSolver {
public:
  virtual ~PressureSolver() = default;
  virtual std::string name() const = 0;
  //! Solves A p = b on the fluid cells of `op` (p is resized to the cell count; empty cells 0).
  //! `p` holds the initial guess on entry when it has the right size.
  virtual SolveResult solve(const CellOperator<dim>& op, const std::vector<double>& b, std::vector<double>& p,
                            const SolveControl& control) = 0;
  //! Drops what the back-end keeps from one solve to the next (MGPCG's hierarchy): the next
  //! solve starts as the first of a run. Called where a restart can begin (frame ends).
  virtual void forget() {}
};

//! Names accepted by make_pressure_solver, in the order of docs/user_guide.md.
std::vector<std::string> pressure_solver_names();

//! "mgpcg" (default), "cg", "jacobi_pcg", "cholmod", "hypre_pfmg", "hypre_boomeramg".
//! Throws mpm::InputError listing the accepted names for any other. `setup_reuse`: the solves
//! one MGPCG hierarchy may serve (mgpcg.h; 1: a new one every solve).
template <int dim>
std::unique_ptr<PressureSolver<dim>> make_pressure_solver(const std::string& name, int setup_reuse = 1);

}  // namespace fluid
