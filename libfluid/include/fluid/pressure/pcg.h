#pragma once
//! Preconditioned conjugate gradients on vectors over the cells of a CellOperator (STYLE.md:
//! the operator and the preconditioner are arguments, the control goes in and the result
//! comes out). Works for the singular NodeCell operator when b is in its range (b = -D u with
//! u = 0 on beta = 0 nodes) and M is symmetric positive semi-definite and positive on range(A):
//! iterates then differ from a solution only by null-space components, which D^T removes.
#include <fluid/pressure/pressure_solver.h>

#include <functional>
#include <vector>

namespace fluid {

//! y = L x for a linear map on cell vectors (y has the size of x).
using LinearMap = std::function<void(const std::vector<double>& x, std::vector<double>& y)>;

//! The Euclidean inner product of two cell vectors of equal size.
double dot(const std::vector<double>& x, const std::vector<double>& y);

//! Solves A p = b from the initial guess in p; `precondition` empty means M = I.
//! The stopping test uses the recurrence residual; the returned residuals are recomputed
//! from b - A p. Setup seconds are left 0 (the caller adds its own setup).
SolveResult pcg(const LinearMap& A, const LinearMap& precondition, const std::vector<double>& b,
                std::vector<double>& p, const SolveControl& control);

}  // namespace fluid
