// hypre IJ BoomerAMG-PCG back-end (see hypre_boomeramg.h). Rows are the fluid cells in
// ascending cell order, filled from CellOperator::for_each_entry, less one pivot cell per null
// vector of a singular operator (detail::pin_null_space), where p = 0.
#include <fluid/pressure/hypre_boomeramg.h>

#include "fluid_cells.h"
#include "hypre_runtime.h"

#include <HYPRE.h>
#include <HYPRE_parcsr_ls.h>
#include <mpi.h>

#include <chrono>

namespace fluid {

template <int dim>
SolveResult HypreBoomerAmgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b_in,
                                             std::vector<double>& p, const SolveControl& control) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  detail::ensure_hypre_initialized();
  std::vector<double> b;
  SolveResult result;
  if (detail::begin_solve(op, b_in, p, b, result)) return result;
  const CellOperator<dim> pinned = detail::pin_null_space(op);
  std::vector<std::int64_t> compact, cell_of;
  const std::int64_t n = detail::number_fluid_cells(pinned, compact, cell_of);

  HYPRE_IJMatrix A;
  HYPRE_IJMatrixCreate(MPI_COMM_WORLD, 0, static_cast<HYPRE_BigInt>(n - 1), 0, static_cast<HYPRE_BigInt>(n - 1), &A);
  HYPRE_IJMatrixSetObjectType(A, HYPRE_PARCSR);
  HYPRE_IJMatrixInitialize(A);
  std::vector<HYPRE_BigInt> columns;
  std::vector<double> values;
  HYPRE_BigInt current = -1;
  auto flush = [&] {
    if (current < 0) return;
    auto count = static_cast<HYPRE_Int>(columns.size());
    HYPRE_IJMatrixSetValues(A, 1, &count, &current, columns.data(), values.data());
    columns.clear();
    values.clear();
  };
  pinned.for_each_entry([&](std::int64_t row, std::int64_t col, double v) {
    if (compact[row] != current) {
      flush();
      current = compact[row];
    }
    columns.push_back(compact[col]);
    values.push_back(v);
  });
  flush();
  HYPRE_IJMatrixAssemble(A);
  HYPRE_ParCSRMatrix parcsr_A;
  HYPRE_IJMatrixGetObject(A, reinterpret_cast<void**>(&parcsr_A));

  std::vector<HYPRE_BigInt> rows(static_cast<std::size_t>(n));
  std::vector<double> b_values(static_cast<std::size_t>(n)), x_values(static_cast<std::size_t>(n));
  for (std::int64_t j = 0; j < n; ++j) {
    rows[j] = j;
    b_values[j] = b[cell_of[j]];
    x_values[j] = p[cell_of[j]];
  }
  HYPRE_IJVector hb, hx;
  for (auto [vector, data] : {std::pair{&hb, &b_values}, std::pair{&hx, &x_values}}) {
    HYPRE_IJVectorCreate(MPI_COMM_WORLD, 0, static_cast<HYPRE_BigInt>(n - 1), vector);
    HYPRE_IJVectorSetObjectType(*vector, HYPRE_PARCSR);
    HYPRE_IJVectorInitialize(*vector);
    HYPRE_IJVectorSetValues(*vector, static_cast<HYPRE_Int>(n), rows.data(), data->data());
    HYPRE_IJVectorAssemble(*vector);
  }
  HYPRE_ParVector par_b, par_x;
  HYPRE_IJVectorGetObject(hb, reinterpret_cast<void**>(&par_b));
  HYPRE_IJVectorGetObject(hx, reinterpret_cast<void**>(&par_x));

  HYPRE_Solver solver, amg;
  HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &solver);
  HYPRE_PCGSetTol(solver, control.relative_tolerance);
  HYPRE_PCGSetAbsoluteTol(solver, control.absolute_tolerance);
  HYPRE_PCGSetMaxIter(solver, control.max_iterations);
  HYPRE_PCGSetTwoNorm(solver, 1);
  HYPRE_BoomerAMGCreate(&amg);
  HYPRE_BoomerAMGSetPrintLevel(amg, 0);
  HYPRE_BoomerAMGSetRelaxType(amg, 6);  // symmetric hybrid Gauss-Seidel: a symmetric V-cycle
  HYPRE_BoomerAMGSetNumSweeps(amg, 1);
  HYPRE_BoomerAMGSetStrongThreshold(amg, dim == 3 ? 0.5 : 0.25);  // hypre's advice for 2D / 3D Laplacians
  HYPRE_BoomerAMGSetMaxIter(amg, 1);
  HYPRE_BoomerAMGSetTol(amg, 0.0);
  HYPRE_PCGSetPrecond(solver, reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSolve),
                      reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSetup), amg);
  HYPRE_ParCSRPCGSetup(solver, parcsr_A, par_b, par_x);
  result.setup_seconds = std::chrono::duration<double>(clock::now() - start).count();
  const auto solve_start = clock::now();
  HYPRE_ParCSRPCGSolve(solver, parcsr_A, par_b, par_x);
  result.solve_seconds = std::chrono::duration<double>(clock::now() - solve_start).count();
  HYPRE_Int iterations = 0;
  HYPRE_PCGGetNumIterations(solver, &iterations);
  result.iterations = static_cast<int>(iterations);
  HYPRE_IJVectorGetValues(hx, static_cast<HYPRE_Int>(n), rows.data(), x_values.data());
  for (std::int64_t c = 0; c < pinned.cell_count(); ++c) p[c] = 0.0;  // the pivots: p = 0
  for (std::int64_t j = 0; j < n; ++j) p[cell_of[j]] = x_values[j];
  HYPRE_BoomerAMGDestroy(amg);
  HYPRE_ParCSRPCGDestroy(solver);
  HYPRE_IJVectorDestroy(hx);
  HYPRE_IJVectorDestroy(hb);
  HYPRE_IJMatrixDestroy(A);
  detail::measure_residual(op, b, p, control, result);
  return result;
}

template class HypreBoomerAmgSolver<2>;
template class HypreBoomerAmgSolver<3>;

}  // namespace fluid
