#pragma once
//! The grid nodes whose velocity a wall or collider prescribes, shared by the fluid stages that
//! must leave those nodes alone (the pressure acts on them with beta = 0, or along a slipping
//! obstacle only, the viscous solve takes them as Dirichlet data).
#include <mpm/core/sparse_grid.h>
#include <mpm/geometry/collider.h>

#include <cstdint>
#include <optional>
#include <vector>

namespace fluid::stages {

//! 1 for every grid storage node with mass whose velocity `colliders` constrains at time t [s],
//! else 0. A node is constrained when ColliderSet::project changes either of the probe
//! velocities a and -a (a generic, non-axis-aligned vector): sticky and slip obstacles change
//! every generic probe, a separating one changes the probe that points into it. So the mask
//! is exactly the set of nodes inside an obstacle or a closed wall layer, for every contact
//! type and obstacle shape, without a second definition of "inside".
template <int dim>
std::vector<std::uint8_t> prescribed_nodes(const mpm::SparseGrid<dim>& grid,
                                           const mpm::geometry::ColliderSet<dim>& colliders, double t);

//! How the pressure may move a prescribed node at x at time t: nullopt where the obstacles hold
//! every component of its velocity (sticky contact, or slipping obstacles whose normals span
//! the space); else P, the orthogonal projector onto the directions they leave free (slip
//! contact, and separating contact, which holds the normal velocity of a node that approaches
//! it or rests on it): I - n n^T along one wall, e e^T along the edge of two in 3D, I where
//! nothing holds it.
template <int dim>
std::optional<mpm::Mat<dim>> slip_directions(const mpm::geometry::ColliderSet<dim>& colliders, const mpm::Vec<dim>& x,
                                             double t);

//! The same test for one storage node k (with mass) only.
template <int dim>
bool is_prescribed(const mpm::SparseGrid<dim>& grid, const mpm::geometry::ColliderSet<dim>& colliders, std::size_t k,
                   double t);

}  // namespace fluid::stages
