#pragma once
//! Matrix-free geometric multigrid V-cycle on the cells of a CellOperator, used as the
//! preconditioner of CG (McAdams, Sifakis & Teran 2010, "A parallel multigrid Poisson solver
//! for fluids simulation on large grids").
//!
//!  * Coarsening: cells aggregate 2^dim -> 1 (odd counts round up); a coarse cell is fluid if
//!    any child is. The coarse operator is rediscretised at 2 dx with the same kind:
//!    Poisson: the same stencil; NodeCell: beta at coarse node N is injected from fine node 2N
//!    (clamped to the last fine node). Injection keeps beta = 0 exactly on wall nodes, which
//!    averaging would smear into the first fluid layer and so turn Neumann walls into leaks.
//!  * Transfers: P is cell-centred multilinear interpolation (weights 3/4, 1/4 per axis,
//!    constant extrapolation at the box faces), R = P^T / 2^dim, so that R A P ~ A_2dx.
//!  * Smoother: damped Jacobi, omega = 4 / (3 lambda_max(D^-1 A)) with lambda_max estimated
//!    by power iteration per level (2/3 for the Laplacian; the 3D NodeCell operator has
//!    positive off-diagonals and lambda_max = 8/3, so a fixed 2/3 would diverge there).
//!  * Bottom: the Moore-Penrose pseudo-inverse of the coarsest matrix (dense, <= a few
//!    hundred fluid cells), which also covers the singular closed-box NodeCell operator.
//! The same number of Jacobi sweeps before and after the coarse correction and R = c P^T make
//! the V-cycle a symmetric positive semi-definite linear map, so CG stays valid.
#include <fluid/pressure/cell_operator.h>

#include <Eigen/Dense>

#include <vector>

namespace fluid {

template <int dim>
class Multigrid {
public:
  struct Options {
    int smoothing_sweeps = 2;           //!< Jacobi sweeps before and after each coarse correction
    std::int64_t max_coarse_cells = 512;  //!< coarsen until the coarsest level has at most this many fluid cells
  };

  //! Builds the hierarchy; `fine` must outlive the Multigrid.
  explicit Multigrid(const CellOperator<dim>& fine, const Options& options);
  explicit Multigrid(const CellOperator<dim>& fine) : Multigrid(fine, Options{}) {}

  //! z = M r: one V-cycle from z = 0 (z resized to the cell count; empty cells 0).
  void apply(const std::vector<double>& r, std::vector<double>& z);

  int level_count() const { return static_cast<int>(levels_.size()); }

private:
  struct Level {
    CellOperator<dim> op;                  //!< empty for level 0, which uses *fine_
    std::vector<double> inverse_diagonal;  //!< 0 for empty cells and zero rows
    double omega = 0.0;
    std::vector<double> b, x, r, scratch;  //!< rhs, iterate, residual, node scratch
  };

  const CellOperator<dim>& op(int level) const { return level == 0 ? fine_ : levels_[level].op; }
  void smooth(int level);
  void vcycle(int level);
  void prolong_add(int coarse_level);
  void restrict_residual(int fine_level);

  const CellOperator<dim>& fine_;
  Options options_;
  std::vector<Level> levels_;
  std::vector<std::int64_t> bottom_cells_;  //!< fluid cells of the coarsest level
  Eigen::MatrixXd bottom_pinv_;
};

}  // namespace fluid
