#pragma once
//! Standard pressure problems shared by the tests and bench_pressure, so both measure the same
//! systems. All live in the unit box [0, 1]^dim with n cells per axis (dx = 1/n) and walls
//! (beta = 0 on every node of the box faces that are not periodic).
#include <fluid/pressure/cell_operator.h>

#include <vector>

namespace fluid {

template <int dim>
using OperatorKind = typename CellOperator<dim>::Kind;

//! Dam break: water fills x < 1/2 and the lower half of the last (vertical) axis (all y in 3D);
//! the other cells are empty (free surface). beta varies smoothly by a factor 3 around
//! beta0 = dt/rho_w = 1e-6 m^3 s/kg (dt = 1e-3 s, rho_w = 1000 kg/m^3) to exercise variable
//! coefficients.
template <int dim>
CellOperator<dim> dam_break_problem(int n, OperatorKind<dim> kind);

//! Every cell fluid, walls on all faces: the NodeCell operator is then singular (constants
//! and checkerboard modes), the Poisson one (p = 0 outside the box) is not.
template <int dim>
CellOperator<dim> closed_box_problem(int n, OperatorKind<dim> kind);

//! Every cell fluid, every axis periodic, no walls (beta > 0 on every node): A is singular
//! (constants; for NodeCell with even n also the checkerboards).
template <int dim>
CellOperator<dim> periodic_box_problem(int n, OperatorKind<dim> kind);

//! A periodic channel: x periodic, walls on the other faces, water in the lower half of the
//! last axis below a free surface (A nonsingular).
template <int dim>
CellOperator<dim> periodic_channel_problem(int n, OperatorKind<dim> kind);

//! The NodeCell periodic channel with a pile through its water: the nodes within radius 0.2 of
//! the axis (x_0, .., x_{dim-2}) = 1/2 (a vertical slab in 2D, a cylinder in 3D) are the
//! obstacle; those within dx of its surface slip along it (P = I - n n^T, n the normal of the
//! surface), the deeper ones are held (beta = 0). Cells without a free corner are empty.
template <int dim>
CellOperator<dim> pile_channel_problem(int n);

//! A pseudo-random nodal velocity [m/s] that is 0 on beta = 0 (wall) nodes and tangential on
//! slipping ones, so that b = -D u lies in the range of A (the obstacles are at rest).
template <int dim>
std::vector<Vec<dim>> wall_consistent_velocity(const CellOperator<dim>& op, unsigned seed);

}  // namespace fluid
