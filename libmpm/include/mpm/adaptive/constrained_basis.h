#pragma once
//! The C0 piecewise-multilinear basis with constrained T-junctions (Gao et al. 2017, sec. 5.2,
//! eq. 11-14) on a CellTree.
//!
//! A lattice point is a *real* node (a degree of freedom) when it is a corner of the coarsest
//! leaf whose closure contains it; it then lives on that leaf's level, its *home*. Any other
//! point (a T-junction on a coarse face, or a point inside a coarse leaf) is *embedded*: its
//! value is the multilinear interpolation of the corners of that coarsest leaf, and a corner
//! that is itself a T-junction is embedded again, in a strictly coarser leaf, until only real
//! nodes remain. Each step uses multilinear weights, so the embedding weights are
//! non-negative, sum to one and reproduce linear fields; the field is continuous across
//! leaves of any level difference (non-graded), because a point has one value whichever leaf
//! it is reached from. The basis function N_i of a real node is the field with value 1 at i
//! and 0 at the other real nodes; GIMP weights (eq. 4) convolve it with the particle box.
#include <mpm/adaptive/cell_tree.h>

#include <vector>

namespace mpm::adaptive {

//! A real node and a weight: the node is lattice point `point`, stored on level `level`.
template <int dim>
struct NodeWeight {
  IVec<dim> point;
  int level;
  double weight;
};

//! Home level of lattice point `point` when it is a real node, -1 otherwise (embedded or
//! outside the domain).
template <int dim>
int home_level(const CellTree<dim>& tree, const IVec<dim>& point);

//! Appends to `out` the real nodes i and weights E_i (times `scale`) with
//! value(point) = sum_i E_i value(i): one entry of weight 1 for a real node. Entries for the
//! same node are merged. Throws InputError for a point outside the domain.
template <int dim>
void embed(const CellTree<dim>& tree, const IVec<dim>& point, double scale, std::vector<NodeWeight<dim>>& out);

//! N_i(x) of every real node i whose basis function is non-zero at position x [m], evaluated
//! in the leaf (level, cell), which must contain x in its closure. A reference evaluation for
//! tests and output: the transfers never call it.
template <int dim>
std::vector<NodeWeight<dim>> basis_in_leaf(const CellTree<dim>& tree, int level, const IVec<dim>& cell,
                                           const Vec<dim>& x);

//! basis_in_leaf in the leaf that contains x (empty outside the domain).
template <int dim>
std::vector<NodeWeight<dim>> basis_at(const CellTree<dim>& tree, const Vec<dim>& x);

}  // namespace mpm::adaptive
