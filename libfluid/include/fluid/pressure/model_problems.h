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

//! A pseudo-random nodal velocity [m/s] that is 0 on beta = 0 (wall) nodes, so that
//! b = -D u lies in the range of A (the wall velocity is prescribed, here at rest).
template <int dim>
std::vector<Vec<dim>> wall_consistent_velocity(const CellOperator<dim>& op, unsigned seed);

}  // namespace fluid
