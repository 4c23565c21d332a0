#pragma once
//! Private: what every back-end does to b and p before it solves on the fluid cells only.
#include <fluid/pressure/cell_operator.h>
#include <fluid/pressure/null_space.h>
#include <fluid/pressure/pressure_solver.h>

#include "cell_kernels.h"

#include <algorithm>
#include <cmath>

#include <cstdint>
#include <vector>

namespace fluid::detail {

//! The operator of `op` as a linear map y = A x for mpm::solve::conjugate_gradient; owns the
//! nodal scratch of the NodeCell product so that iterations do not reallocate it.
template <int dim>
class OperatorProduct {
public:
  explicit OperatorProduct(const CellOperator<dim>& op) : op_(op) {}
  void apply(const std::vector<double>& x, std::vector<double>& y) { apply_operator(op_, x, y, scratch_); }

private:
  const CellOperator<dim>& op_;
  std::vector<double> scratch_;
};

//! b restricted to fluid cells (empty cells 0), so that residuals measure fluid cells only.
template <int dim>
std::vector<double> fluid_rhs(const CellOperator<dim>& op, const std::vector<double>& b) {
  std::vector<double> masked(static_cast<std::size_t>(op.cell_count()), 0.0);
  for (std::size_t c = 0; c < masked.size(); ++c)
    if (op.type[c] == CellType::fluid) masked[c] = b[c];
  return masked;
}

//! Keeps the initial guess when it has the cell count (else 0) and sets p = 0 in empty cells.
template <int dim>
void prepare_guess(const CellOperator<dim>& op, std::vector<double>& p) {
  const auto n = static_cast<std::size_t>(op.cell_count());
  if (p.size() != n) p.assign(n, 0.0);
  for (std::size_t c = 0; c < n; ++c)
    if (op.type[c] != CellType::fluid) p[c] = 0.0;
}

//! For b = 0 on the fluid cells the solution is p = 0 (there is no relative target to iterate
//! to): sets p and result and returns true; otherwise returns false.
inline bool solved_for_zero_rhs(const std::vector<double>& b, std::vector<double>& p, SolveResult& result) {
  if (!std::all_of(b.begin(), b.end(), [](double v) { return v == 0.0; })) return false;
  std::fill(p.begin(), p.end(), 0.0);
  result = SolveResult{};
  result.converged = true;
  return true;
}

//! The start of every solve that is not plain PCG: b restricted to the fluid cells (into
//! `b`), p prepared as the initial guess; true when b = 0, with p = 0 and `result` final.
template <int dim>
bool begin_solve(const CellOperator<dim>& op, const std::vector<double>& b_in, std::vector<double>& p,
                 std::vector<double>& b, SolveResult& result) {
  b = fluid_rhs(op, b_in);
  prepare_guess(op, p);
  return solved_for_zero_rhs(b, p, result);
}

//! Compact numbering of the fluid cells (-1 for empty cells) and its inverse.
template <int dim>
std::int64_t number_fluid_cells(const CellOperator<dim>& op, std::vector<std::int64_t>& compact,
                                std::vector<std::int64_t>& cell_of) {
  compact.assign(static_cast<std::size_t>(op.cell_count()), -1);
  cell_of.clear();
  for (std::size_t c = 0; c < compact.size(); ++c)
    if (op.type[c] == CellType::fluid) {
      compact[c] = static_cast<std::int64_t>(cell_of.size());
      cell_of.push_back(static_cast<std::int64_t>(c));
    }
  return static_cast<std::int64_t>(cell_of.size());
}

//! Fills the residuals of `result` from b - A p (b already masked) and sets `converged` by the
//! control, so that back-ends with their own stopping tests report the same measure.
template <int dim>
void measure_residual(const CellOperator<dim>& op, const std::vector<double>& b, const std::vector<double>& p,
                      const SolveControl& control, SolveResult& result) {
  std::vector<double> Ap, scratch;
  apply_operator(op, p, Ap, scratch);
  double r2 = 0.0, b2 = 0.0;
  for (std::size_t c = 0; c < b.size(); ++c) {
    r2 += (b[c] - Ap[c]) * (b[c] - Ap[c]);
    b2 += b[c] * b[c];
  }
  result.absolute_residual = std::sqrt(r2);
  result.relative_residual = b2 > 0.0 ? result.absolute_residual / std::sqrt(b2) : 0.0;
  // A factor 10 above the target covers the drift between a solver's own residual and ours.
  const double target = std::max(control.relative_tolerance * std::sqrt(b2), control.absolute_tolerance);
  result.converged = std::isfinite(r2) && result.absolute_residual <= 10.0 * target;
}

//! `op` with p = 0 in one pivot cell per null vector of null_space.h (the cells made empty), so
//! that its matrix on the fluid cells is nonsingular for back-ends whose coarse levels cannot
//! cope with a singular system (hypre: BoomerAMG-PCG stalled near 1e-7 on the periodic box).
//! For b orthogonal to the null vectors the pivot rows then hold as well: A p = b on every cell.
//! The pivots come from Gaussian elimination with partial pivoting on the basis, so the basis
//! restricted to them is nonsingular.
template <int dim>
CellOperator<dim> pin_null_space(const CellOperator<dim>& op) {
  CellOperator<dim> pinned = op;
  std::vector<std::vector<double>> basis = null_space_basis(op);
  for (std::size_t j = 0; j < basis.size(); ++j) {
    const auto& q = basis[j];
    std::size_t pivot = 0;
    for (std::size_t c = 1; c < q.size(); ++c)
      if (std::abs(q[c]) > std::abs(q[pivot])) pivot = c;
    pinned.type[pivot] = CellType::empty;
    for (std::size_t l = j + 1; l < basis.size(); ++l) {
      const double factor = basis[l][pivot] / q[pivot];
      for (std::size_t c = 0; c < q.size(); ++c) basis[l][c] -= factor * q[c];
    }
  }
  return pinned;
}

}  // namespace fluid::detail
