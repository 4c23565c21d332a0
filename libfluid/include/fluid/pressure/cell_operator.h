#pragma once
//! The pressure operator of the projection, matrix-free, on a dense box of cells.
//!
//! Unknowns p_c live at cell centres; velocities at the nodes (cell corners) of the same box
//! (semi-staggered grid). Cells are fluid (an unknown) or empty (p = 0, free
//! surface); every other cell is also p = 0, and walls enter through node coefficients.
//!
//! Two operators share this interface:
//!  * NodeCell (the project's own): A = D B D^T, with
//!      (D u)_c = exact cell average of div u for the multilinear nodal field u
//!              = sum_{corners i of c} sum_a s_{c,i,a} u_{i,a} / (2^{dim-1} dx),
//!      s_{c,i,a} = +1 if corner i is on the upper side of c along axis a, else -1,
//!      B = diag(beta_i P_i) per node (beta_i = dt (n_w/rho_w + n_s/rho_s) [m^3 s/kg]; 0 on nodes
//!      whose velocity is prescribed by a wall or collider, which is how Neumann walls enter;
//!      P_i the orthogonal projector onto the velocity directions that no obstacle holds at a
//!      node slipping along one (I - n_i n_i^T on a wall of unit normal n_i, e_i e_i^T along
//!      the edge where two walls meet in 3D), whose held components the pressure leaves and
//!      whose free ones it moves; P_i = I elsewhere),
//!    so that u <- u - B G p = u + B D^T p (G = -D^T, the discrete gradient) with
//!    A p = b, b = -D u, makes D u = 0 in every fluid cell. A is symmetric
//!    positive semi-definite; on a uniform box it has checkerboard null modes besides constants.
//!  * Poisson (the standard 2*dim+1-point Laplacian, for benchmarks against hypre):
//!      (A p)_c = sum_{faces f of c} (p_c - p_nb) / dx^2, neighbour outside the box or empty: p_nb = 0.
//! Both are stored as a cell-type mask plus per-node (NodeCell) coefficients; solvers apply A
//! matrix-free and may assemble it (CHOLMOD, hypre) through for_each_entry.
//!
//! Periodic axes: cell c + cells[a] e_a is cell c and node n + cells[a] e_a is node n, so the
//! box has cells[a] nodes along a (no face) and every stencil wraps; a periodic axis needs at
//! least 2 cells. A fully periodic box of fluid cells has no p = 0 cell: A is singular with the
//! constants (and, for NodeCell with even counts, the checkerboards) as null vectors; b must be
//! in the range of A (null_space.h makes it so and fixes the pressure level).
#include <mpm/core/types.h>

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace fluid {

using mpm::IVec;
using mpm::Mat;
using mpm::Vec;

enum class CellType : std::uint8_t { empty = 0, fluid = 1 };

template <int dim>
struct CellOperator {
  enum class Kind { node_cell, poisson };
  Kind kind = Kind::node_cell;
  IVec<dim> cells = IVec<dim>::Zero();  //!< cells per axis; nodes per axis = cells + 1
  double dx = 1.0;                      //!< [m]
  std::vector<CellType> type;           //!< per cell, x fastest
  std::vector<double> beta;             //!< per node, x fastest (NodeCell only)
  //! Slipping nodes (NodeCell only; both empty when none): slip_index[i] >= 0 makes
  //! P_i = slip_projector[slip_index[i]], -1 makes P_i = I (per node, x fastest).
  std::vector<std::int32_t> slip_index;
  std::vector<Mat<dim>> slip_projector;
  std::array<bool, dim> periodic{};  //!< per axis (see above)

  bool is_periodic() const;
  //! Nodes per axis: cells + 1, or cells on a periodic axis.
  IVec<dim> node_extent() const;
  std::int64_t cell_count() const;
  std::int64_t node_count() const;
  std::int64_t cell_index(const IVec<dim>& c) const;  //!< x fastest
  //! x fastest; on a periodic axis node cells[a] is node 0.
  std::int64_t node_index(IVec<dim> n) const;

  //! y = A x over all cells (y_c = 0 for empty cells; x is read only at fluid cells).
  void apply(const std::vector<double>& x, std::vector<double>& y) const;
  //! Whether some node slips (P_i != I somewhere).
  bool has_slip() const { return !slip_index.empty(); }
  //! Makes P_i = free, an orthogonal projector.
  void set_slip(std::int64_t i, const Mat<dim>& free);
  //! P_i = I everywhere.
  void clear_slip();
  //! P_i.
  Mat<dim> free_directions(std::int64_t i) const {
    const std::int32_t j = has_slip() ? slip_index[static_cast<std::size_t>(i)] : -1;
    return j < 0 ? Mat<dim>::Identity() : slip_projector[static_cast<std::size_t>(j)];
  }
  //! beta_i P_i g: the mobility of node i applied to a nodal vector g.
  Vec<dim> mobility(std::int64_t i, const Vec<dim>& g) const {
    const double b = beta[static_cast<std::size_t>(i)];
    const std::int32_t j = has_slip() ? slip_index[static_cast<std::size_t>(i)] : -1;
    return j < 0 ? Vec<dim>(b * g) : Vec<dim>(b * (slip_projector[static_cast<std::size_t>(j)] * g));
  }
  //! Makes empty every fluid cell whose corners all have beta = 0 (NodeCell: a particle inside
  //! a wall): no unknown could change its divergence, so it would make the system inconsistent.
  void empty_cells_without_unknowns();
  //! The diagonal of A (0 for empty cells).
  void diagonal(std::vector<double>& d) const;
  //! Calls f(row cell, column cell, value) for every nonzero of A between fluid cells,
  //! row by row, columns ascending, each column once (for assembly by direct and algebraic
  //! solvers).
  void for_each_entry(const std::function<void(std::int64_t, std::int64_t, double)>& f) const;
  //! for_each_entry over the rows of the cells with box index in [first, last) only (x
  //! fastest), so that an assembly can split the rows among threads.
  void for_each_entry(std::int64_t first, std::int64_t last,
                      const std::function<void(std::int64_t, std::int64_t, double)>& f) const;

  //! rhs of the projection: b_c = -(D u)_c for fluid cells, 0 elsewhere (u per node, x fastest).
  void divergence(const std::vector<Vec<dim>>& u, std::vector<double>& div) const;
  //! u_i += beta_i P_i (D^T p)_i (= u_i - beta_i P_i (G p)_i) for every node.
  void subtract_gradient(const std::vector<double>& p, std::vector<Vec<dim>>& u) const;
};

}  // namespace fluid
