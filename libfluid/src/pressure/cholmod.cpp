// CHOLMOD back-end (regularisation documented in cholmod.h).
#include <fluid/pressure/cholmod.h>

#include "cell_kernels.h"
#include "fluid_cells.h"

#include <mpm/core/error.h>

#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace fluid {

namespace {
//! Owns a cholmod_common for the lifetime of one solve.
struct CholmodCommon {
  cholmod_common c;
  CholmodCommon() {
    cholmod_start(&c);
    c.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~CholmodCommon() { cholmod_finish(&c); }
  CholmodCommon(const CholmodCommon&) = delete;
  CholmodCommon& operator=(const CholmodCommon&) = delete;
};
}  // namespace

template <int dim>
SolveResult CholmodSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b_in,
                                      std::vector<double>& p, const SolveControl& control) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  std::vector<double> b;
  SolveResult result;
  if (detail::begin_solve(op, b_in, p, b, result)) return result;
  std::vector<std::int64_t> compact, cell_of;
  const std::int64_t n = detail::number_fluid_cells(op, compact, cell_of);
  // Upper triangle in compressed columns: column j = the entries of row j with column <= j
  // (A is symmetric), which for_each_entry delivers row by row, columns ascending.
  std::vector<int> column_start{0}, row_index;
  std::vector<double> value;
  double max_diagonal = 0.0;
  std::int64_t current_row = 0;
  op.for_each_entry([&](std::int64_t row, std::int64_t col, double v) {
    const std::int64_t r = compact[row], c = compact[col];
    while (current_row < r) {
      column_start.push_back(static_cast<int>(row_index.size()));
      ++current_row;
    }
    if (c > r) return;
    row_index.push_back(static_cast<int>(c));
    value.push_back(v);
    if (c == r) max_diagonal = std::max(max_diagonal, v);
  });
  while (current_row < n) {
    column_start.push_back(static_cast<int>(row_index.size()));
    ++current_row;
  }
  const double eps = 1e-12 * max_diagonal;
  for (std::int64_t j = 0; j < n; ++j) {
    const int last = column_start[j + 1] - 1;
    mpm::verify<mpm::NumericalError>(last >= column_start[j] && row_index[last] == j,
                                     "cholmod: fluid cell " + std::to_string(cell_of[j]) + " has no diagonal entry");
    value[last] += eps;
  }

  CholmodCommon common;
  cholmod_sparse A{};
  A.nrow = A.ncol = static_cast<std::size_t>(n);
  A.nzmax = value.size();
  A.p = column_start.data();
  A.i = row_index.data();
  A.x = value.data();
  A.stype = 1;
  A.itype = CHOLMOD_INT;
  A.xtype = CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1;
  A.packed = 1;
  cholmod_factor* L = cholmod_analyze(&A, &common.c);
  mpm::verify<mpm::NumericalError>(L != nullptr, "cholmod: cholmod_analyze failed");
  cholmod_factorize(&A, L, &common.c);
  const bool factored = common.c.status == CHOLMOD_OK && L->minor == L->n;
  result.setup_seconds = std::chrono::duration<double>(clock::now() - start).count();
  if (!factored) {
    cholmod_free_factor(&L, &common.c);
    throw mpm::NumericalError("cholmod: factorisation of A + eps I failed (status " + std::to_string(common.c.status) +
                              ", matrix not positive semi-definite?)");
  }

  const auto solve_start = clock::now();
  cholmod_dense* residual = cholmod_zeros(static_cast<std::size_t>(n), 1, CHOLMOD_REAL, &common.c);
  auto* r = static_cast<double*>(residual->x);
  std::vector<double> Ap, scratch;
  double b_norm = 0.0;
  for (double v : b) b_norm += v * v;
  b_norm = std::sqrt(b_norm);
  const double target = std::max(control.relative_tolerance * b_norm, control.absolute_tolerance);
  constexpr int max_refinements = 50;  // refinement stagnates at round-off well before
  for (;;) {
    detail::apply_operator(op, p, Ap, scratch);
    double norm = 0.0;
    for (std::int64_t j = 0; j < n; ++j) {
      r[j] = b[cell_of[j]] - Ap[cell_of[j]];
      norm += r[j] * r[j];
    }
    result.absolute_residual = std::sqrt(norm);
    result.relative_residual = b_norm > 0.0 ? result.absolute_residual / b_norm : 0.0;
    result.converged = result.absolute_residual <= target;
    if (result.converged || result.iterations >= std::min(control.max_iterations, max_refinements) ||
        !std::isfinite(norm))
      break;
    cholmod_dense* correction = cholmod_solve(CHOLMOD_A, L, residual, &common.c);
    const auto* dp = static_cast<const double*>(correction->x);
    for (std::int64_t j = 0; j < n; ++j) p[cell_of[j]] += dp[j];
    cholmod_free_dense(&correction, &common.c);
    ++result.iterations;
  }
  cholmod_free_dense(&residual, &common.c);
  cholmod_free_factor(&L, &common.c);
  result.solve_seconds = std::chrono::duration<double>(clock::now() - solve_start).count();
  return result;
}

template class CholmodSolver<2>;
template class CholmodSolver<3>;

}  // namespace fluid
