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
//!  * Transfers: P is cell-centred multilinear interpolation (weights 3/4, 1/4 per axis),
//!    R = P^T / 2^dim, so that R A P ~ A_2dx; both are applied one axis at a time. At the box
//!    faces the missing coarse neighbour is the mirror image of the nearest coarse cell:
//!    -x for Poisson (p = 0 on the face: Dirichlet), +x for NodeCell (walls: Neumann), as the
//!    fine operator does. Constant extrapolation at the faces let the Poisson iteration count
//!    grow with resolution; the mirror image keeps it flat (docs/performance.md, 'Multigrid
//!    design measurements').
//!  * Smoother: Poisson: red-black Gauss-Seidel (same-colour cells do not couple), red then
//!    black before the coarse correction, black then red after. 2D NodeCell: the same with
//!    columns of even and odd x as the two colours, on the explicit row
//!    (A p)_c = sum_{corners n} beta_n (p_c - p_c'(n)) / (2 dx^2), c'(n) the cell diagonally
//!    across n (the face-neighbour entries vanish, see below); it replaced damped Jacobi, which
//!    needed two products with A per sweep and took more time and iterations
//!    (docs/performance.md, 'Multigrid design measurements'). A periodic x axis with an odd
//!    count is not supported (supports() is false; MGPCG then uses ModulatedMultigrid). 3D
//!    NodeCell is not supported either: its 3^dim stencil couples same-colour cells, and its
//!    near-null space is not smooth (modulated_multigrid.h handles it).
//!  * Bottom: the Moore-Penrose pseudo-inverse of the coarsest matrix (dense), which also
//!    covers the singular closed-box NodeCell operator. The hierarchy is rebuilt every solve,
//!    so coarsening goes down to <= 32 fluid cells: with a larger bottom the dense eigensolve
//!    dominated the set-up and made the pressure solve of small scenes slower than plain CG;
//!    the smaller bottom costs small scenes a few iterations and leaves the bench_pressure
//!    counts about flat (docs/performance.md, 'Multigrid design measurements').
//!  * Checkerboard modes (2D NodeCell): in 2D, A = D B D^T couples only diagonal neighbours
//!    (the face-neighbour entry sums s_x s_x' + s_y s_y' = 0 over the shared corners), so the
//!    red and black cells decouple and S A S = A for S = diag((-1)^(i+j)), for any beta and
//!    free surface. Smooth transfers cannot represent the near-null modes S q (q smooth)
//!    and Jacobi does not reduce them, so the preconditioner is M = V + S V S: the second
//!    V-cycle sees them as smooth. Without the S V S term the iteration count grows with
//!    resolution; with it, it stays flat (docs/performance.md, 'Multigrid design
//!    measurements'). S also commutes with the column smoother (it reads only same-parity
//!    cells), so apply() shares the fine-level smoothing of the two V-cycles (one pre- and one
//!    post-smoothing around both coarse corrections) and builds exactly the same M.
//!    In 3D S A S != A for every sign pattern, and the near-null set is three lines of Fourier
//!    space: modulated_multigrid.h gives each its own Galerkin coarse space.
//!  * Periodic axes: stencils, transfers (the 1/4 neighbour wraps) and smoothers wrap; such an
//!    axis halves only from an even count >= 4, so coarsening stops at the first odd count
//!    (power-of-two periods coarsen fully). The Poisson red-black smoother needs even
//!    periodic counts on the fine level. The bottom pseudo-inverse covers the constant null
//!    mode of a fully periodic box.
//! The post-smoother is the adjoint of the pre-smoother and R = c P^T, so the V-cycle is a
//! symmetric positive semi-definite linear map and CG stays valid.
#include <fluid/pressure/cell_operator.h>

#include <Eigen/Dense>

#include <vector>

namespace fluid {

template <int dim>
class Multigrid {
public:
  struct Options {
    int smoothing_sweeps = 2;            //!< smoothing sweeps before and after each coarse correction
    std::int64_t max_coarse_cells = 32;  //!< coarsen until the coarsest level has at most this many fluid cells
  };

  //! Poisson in 2D and 3D; 2D NodeCell unless the x axis is periodic with an odd count.
  static bool supports(const CellOperator<dim>& op);
  //! Builds the hierarchy; `fine` must outlive the Multigrid and be supported.
  explicit Multigrid(const CellOperator<dim>& fine, const Options& options);
  explicit Multigrid(const CellOperator<dim>& fine) : Multigrid(fine, Options{}) {}

  //! z = M r: one V-cycle from z = 0; for 2D NodeCell M = V + S V S, fused so that the fine
  //! level is smoothed once before and once after the two coarse corrections (z resized to
  //! the cell count; empty cells 0).
  void apply(const std::vector<double>& r, std::vector<double>& z);

  int level_count() const { return static_cast<int>(levels_.size()); }

private:
  struct Level {
    CellOperator<dim> op;                  //!< empty for level 0, which uses *fine_
    std::vector<double> b, x, r, scratch;  //!< rhs, iterate, residual, node scratch
  };

  const CellOperator<dim>& op(int level) const { return level == 0 ? fine_ : levels_[level].op; }
  //! The smoothing before (from x = 0) or after the coarse correction of a V-cycle.
  void smooth(int level, bool before);
  void gauss_seidel(int level, int colour);
  void rotated_gauss_seidel(int level, int parity);
  void vcycle(int level);
  void prolong_add(int coarse_level);
  void restrict_residual(int fine_level);
  void restrict_to_coarse(int fine_level, const std::vector<double>& fine);

  const CellOperator<dim>& fine_;
  Options options_;
  std::vector<Level> levels_;
  std::vector<double> transfer_in_, transfer_out_;  //!< scratch of the axis-by-axis transfers
  std::vector<double> checkerboard_;                //!< S = diag((-1)^(i+j)); empty unless 2D NodeCell
  std::vector<std::int64_t> bottom_cells_;          //!< fluid cells of the coarsest level
  Eigen::MatrixXd bottom_pinv_;
};

}  // namespace fluid
