#pragma once
//! Multigrid for the 3D NodeCell operator, whose near-null space is not smooth: coarse spaces
//! of sign-modulated interpolants, chosen by their energy, with Galerkin coarse operators.
//!
//! Why. In 3D, A = D B D^T (cell_operator.h) has the symbol
//!   4 [s_x c_y c_z + c_x s_y c_z + c_x c_y s_z],  s_a = sin^2(theta_a / 2), c_a = cos^2(theta_a / 2),
//! which vanishes at 0 and on the three lines (pi, pi, t), (pi, t, pi), (t, pi, pi): the modes
//! (-1)^(i+j) f(k) (and permutations) have no nodal gradient for any f. Near (pi, pi, pi) the
//! symbol is quartic (a^2 b^2 + b^2 c^2 + c^2 a^2 in the offsets). A smooth coarse space
//! cannot represent these modes and no point smoother reduces them, so the iteration count of
//! CG with the geometric V-cycle of multigrid.h grows steeply with resolution
//! (docs/performance.md, 'Multigrid design measurements').
//!
//! Construction (recursive, per "space": a matrix over a set of cells of a box):
//!  * P0: cell-centred multilinear interpolation from the 2x-coarser box (weights 3/4, 1/4 per
//!    axis; the 1/4 neighbour is mirrored at a face, wrapped on a periodic axis), with a
//!    column for each coarse cell that has a cell of the space among its children. Cells
//!    whose row has no off-diagonal entry (droplets) get no interpolation: the smoother
//!    solves them exactly.
//!  * For each of the 2^dim sign patterns k (S_k = diag((-1)^(k . c))), the modulated space
//!    P_k = S_k P0 becomes a child when its constant vector v = P_k 1 is near-null: the
//!    median over the cells of (A v)_i / (A_ii v_i) is below near_null_ratio (k = 0 always).
//!    A median, so that a minority of cells (spray) cannot vote a pattern out. On the fine
//!    NodeCell box this picks k = 000, 110, 011, 101, 111: the smooth and the checkerboard
//!    families above.
//!    The child's matrix is the Galerkin product A_k = P_k^T A P_k, and the child is built
//!    the same way, so each family gets its own coarse hierarchy with the near-null patterns
//!    of its own operator at the next scale (the smooth child A_000 is again NodeCell-like;
//!    A_111 is the quartic operator, whose near-null lines lie on the axes). The number of
//!    spaces in the tree grows with resolution (docs/performance.md, 'Multigrid design
//!    measurements').
//!  * Cross terms P_j^T A P_k (j != k) are dropped: each child corrects on its own. For
//!    constant beta on a periodic box the patterns are A-orthogonal harmonics, so this loses
//!    little: in a two-level prototype the separate coarse systems took more iterations than
//!    the coupled one, at a fraction of its nonzeros (docs/performance.md, 'Multigrid design
//!    measurements').
//!  * Combining the children: on the fine space and its children additively (all from one
//!    residual: one product with the space's matrix; the subtrees run in parallel); on every
//!    deeper space multiplicatively, children 0, 1, .., K-1, .., 1, 0, each from the updated
//!    residual. The palindrome keeps the cycle symmetric, and it makes each child's cycle a
//!    convergent iteration (an A-norm contraction), which the additive sum is not where
//!    children overlap: additive on every space let the iteration count grow with resolution
//!    (two cycles per child even broke CG down: the sum overcorrects). Additive on the first
//!    two depths keeps it flat (12 iterations on the 3D dam break from 32^3 to 96^3, against
//!    9-10 with only the fine space additive) and saves 2K - 2 of the 2K - 1 residual
//!    products of each depth-1 space (together 39 % of a cycle's work): the 3D flagship's
//!    solves are faster (docs/performance.md,
//!    'The pressure multigrid's first coarse spaces additive'). Multiplicative on the fine
//!    level too saves iterations but costs more time than it saves ('Multigrid design
//!    measurements'). Whatever the combination, each sum of symmetric positive semi-definite
//!    corrections between adjoint smoothers keeps the cycle symmetric positive definite.
//!  * Smoother: one forward Gauss-Seidel sweep before the coarse corrections and one backward
//!    sweep after (the adjoint), so the cycle is a symmetric positive definite map on the
//!    range of A and CG stays valid. On spaces of at least 4096 unknowns the sweep goes colour
//!    by colour (box coordinates mod 3 per axis: 27 colours in 3D, whose rows, 3 cells apart,
//!    the 5^3 Galerkin stencils never couple), each colour's rows in parallel, and backward
//!    in the reverse colour order; the result does not depend on the thread count.
//!  * Bottom: the Moore-Penrose pseudo-inverse of a space with at most max_bottom_unknowns
//!    unknowns (covers singular closed boxes); a space that can neither coarsen (odd periodic
//!    count) nor be inverted is smoothed only.
//! The iteration count stays flat under refinement where plain CG's grows. The Galerkin
//! stencils have 5^3 points, so the nonzeros of all levels ("operator complexity") are a few
//! times the fine ones and grow slowly with resolution, and the set-up (the Galerkin products)
//! costs about as much as a solve. The fine level's children, the rows of the Galerkin
//! products, the smoother's colours and the rows of the cycle's products run in parallel. docs/performance.md has the figures ('Multigrid design
//! measurements') and compares the other back-ends ('Pressure solvers').
#include <fluid/pressure/cell_operator.h>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace fluid {

template <int dim>
class ModulatedMultigrid {
public:
  struct Options {
    double near_null_ratio = 0.3;           //!< a pattern is a child when its median energy ratio is below this
    std::int64_t max_bottom_unknowns = 64;  //!< invert spaces of at most this many unknowns
    int smoothing_sweeps = 1;               //!< Gauss-Seidel sweeps before and after the coarse corrections
    //! The spaces of depth below this (the fine one: 0) combine their children additively,
    //! deeper ones multiplicatively (header); >= 0
    int additive_depth = 2;
    //! refresh(): the share of the fine cells that may lack their own coarse cell
    double max_orphan_share = 0.02;
  };

  //! Assembles A over the fluid cells of `op` and builds the tree.
  ModulatedMultigrid(const CellOperator<dim>& op, const Options& options);
  explicit ModulatedMultigrid(const CellOperator<dim>& op) : ModulatedMultigrid(op, Options{}) {}

  //! Takes the fine space of `op` (its fluid cells, matrix and smoother) and keeps the coarse
  //! spaces built for an earlier operator on the same box (and periodic axes). Where the fluid
  //! cells changed, P0 interpolates from the coarse cells there are and the sign vectors
  //! follow the cells. The coarse corrections then come from the earlier operator's Galerkin
  //! products, scaled by the ratio of the mean diagonals (the step dt scales the whole
  //! operator: a frame's last, shorter step took 46-68 iterations against 15 without): the
  //! cycle stays symmetric positive definite (adjoint smoothers on the exact
  //! fine matrix around any symmetric positive semi-definite coarse correction), so CG stays
  //! valid and only its rate depends on how far the operator moved. Returns false, and the
  //! tree is then to be built anew, for another box, for changed cells where the tree has no
  //! coarse spaces, or where a coupled cell's own coarse cell is not among them (a cell with a
  //! quarter weight at most converges slowly: 57 CG iterations against 19 in test_pressure).
  bool refresh(const CellOperator<dim>& op);

  //! z = M r for vectors over all cells of the box (empty cells: read as 0, written 0).
  void apply(const std::vector<double>& r, std::vector<double>& z);

  //! Spaces in the tree (the fine one included).
  int space_count() const;
  //! Sign patterns of the fine space's children (bit a of a pattern: sign flips along axis a).
  std::vector<int> fine_patterns() const;
  //! Nonzeros of all matrices over those of the fine one (the cost of a cycle, roughly).
  double operator_complexity() const;

private:
  using Matrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;
  struct Space;
  struct Child {
    int pattern = 0;
    std::unique_ptr<Space> space;  //!< its own subtree: siblings are built in parallel
    Eigen::VectorXd sign;          //!< S_k over the parent's unknowns: P_k = S_k P0
  };
  struct Space {
    Matrix A;
    IVec<dim> extent;             //!< the box the cells live in
    std::vector<IVec<dim>> cell;  //!< box coordinates of each unknown
    Eigen::VectorXd inverse_diagonal;
    std::vector<Child> children;
    Matrix P0, R0;           //!< interpolation from the children's box and its transpose
    Eigen::MatrixXd bottom;  //!< pseudo-inverse; empty unless a bottom space
    Eigen::VectorXd b, x, residual, scratch;
    //! The rows of each colour (box coordinates mod 3 per axis): no row couples to another of
    //! its colour, so a colour's rows relax in parallel; empty: the space is smoothed in order
    //! (small spaces, or a periodic wrap that joins two rows of one colour).
    std::vector<std::vector<int>> colours;
  };

  //! P0 from the cells of `s` onto the coarse cells `coarse_cell` of a box of `coarse_extent`
  //! (weights 3/4, 1/4 per axis; header). The parent of a coupled cell that is missing is
  //! appended with `add_parents` (a new tree), else there is no P0 (refresh: nullopt).
  std::optional<Matrix> interpolation(const Space& s, const IVec<dim>& coarse_extent,
                                      std::vector<IVec<dim>>& coarse_cell, bool add_parents) const;
  //! A over the fluid cells numbered by `compact` (fluid_cells_ set).
  Matrix fine_matrix(const CellOperator<dim>& op, const std::vector<std::int64_t>& compact);
  //! The smoother's data of `s` (its matrix, extent and cells set), or its bottom inverse;
  //! returns whether `s` gets coarse children.
  bool prepare(Space& s) const;
  //! Builds the subtree below `s` (its matrix, extent and cells set); the children's
  //! subtrees in parallel (each touches only its own spaces: the result is the serial one).
  void build(Space& s) const;
  //! `depth`: of `s` in the tree (the root: 0); above Options::additive_depth the children
  //! combine additively (header).
  void cycle(Space& s, int depth);
  void gauss_seidel(Space& s, bool forward) const;
  template <class Fn>
  static void for_each_space(const Space& s, Fn&& fn);

  Options options_;
  std::array<bool, dim> periodic_{};
  std::vector<std::int64_t> fluid_cells_;  //!< box index of each fine unknown
  std::unique_ptr<Space> fine_;            //!< the tree's root
  double built_trace_ = 0.0;               //!< mean diagonal of the fine matrix the tree was built from
  double coarse_scale_ = 1.0;              //!< built_trace_ over that of the refreshed fine matrix
};

}  // namespace fluid
