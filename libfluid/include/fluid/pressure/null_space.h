#pragma once
//! The null space of a CellOperator and what a solve does about it. A closed region (walls
//! all round, or periodic axes) has no p = 0 cell: A p = b is solvable only for b orthogonal to
//! the null vectors of A, and p is fixed only up to them. The candidates are the constant and
//! the checkerboards prod_{a in S} (-1)^{c_a}, |S| >= 2 (the Q1-P0 modes of NodeCell), on the
//! fluid cells; the null vectors are the combinations V alpha with (V^T A V) alpha = 0 (A is
//! positive semi-definite). The projection removes them from b (a consistent right-hand
//! side: round-off and, for a moving lid, the checkerboard it drives) and from p after the
//! solve (the pressure level: p orthogonal to the null space, i.e. zero mean over a fully
//! periodic box, as the analytic pressure of Taylor-Green). The impulse B D^T p does not
//! change: B^{1/2} D^T v = 0 for a null vector v.
#include <fluid/pressure/cell_operator.h>

#include <vector>

namespace fluid {

//! An orthonormal basis of the null vectors of A within the candidates (empty when A is
//! nonsingular on them).
template <int dim>
std::vector<std::vector<double>> null_space_basis(const CellOperator<dim>& op);

//! v minus its components along the orthonormal `basis`.
void remove_components(const std::vector<std::vector<double>>& basis, std::vector<double>& v);

}  // namespace fluid
