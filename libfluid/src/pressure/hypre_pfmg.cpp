// hypre Struct PFMG-PCG back-end (see hypre_pfmg.h). The matrix rows are filled from
// CellOperator::for_each_entry; the stencil offset of an entry is the cell offset col - row,
// taken modulo the period on periodic axes (HYPRE_StructGridSetPeriodic wraps the stencil).
// PFMG-PCG handles the singular periodic box in 2D as it is (pinning null-space pivots, as
// BoomerAMG does, raised its iterations from 38 to 49); it breaks down on the 3D NodeCell
// periodic box, whose null space is larger (multigrid.h), which docs/user_guide.md states.
#include <fluid/pressure/hypre_pfmg.h>

#include "fluid_cells.h"
#include "hypre_runtime.h"

#include <mpm/core/error.h>

#include <HYPRE_struct_ls.h>
#include <mpi.h>

#include <array>
#include <chrono>

namespace fluid {

template <int dim>
SolveResult HyprePfmgSolver<dim>::solve(const CellOperator<dim>& op, const std::vector<double>& b_in,
                                        std::vector<double>& p, const SolveControl& control) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  detail::ensure_hypre_initialized();
  std::vector<double> b;
  SolveResult result;
  if (detail::begin_solve(op, b_in, p, b, result)) return result;
  const bool poisson = op.kind == CellOperator<dim>::Kind::poisson;
  const std::int64_t n = op.cell_count();

  // Stencil: Poisson {0, -e_a, +e_a}; NodeCell all of {-1,0,1}^dim (index sum (o_a + 1) 3^a).
  std::vector<IVec<dim>> offsets;
  if (poisson) {
    offsets.push_back(IVec<dim>::Zero());
    for (int a = 0; a < dim; ++a)
      for (int side : {-1, 1}) offsets.push_back(side * IVec<dim>::Unit(a));
  } else {
    for (int m = 0; m < mpm::ipow(3, dim); ++m) {
      IVec<dim> o;
      for (int a = 0, q = m; a < dim; ++a, q /= 3) o[a] = q % 3 - 1;
      offsets.push_back(o);
    }
  }
  const int entries = static_cast<int>(offsets.size());
  auto stencil_entry = [&](const IVec<dim>& o) {
    if (!poisson) {
      int m = 0;
      for (int a = dim - 1; a >= 0; --a) m = 3 * m + o[a] + 1;
      return m;
    }
    for (int s = 0; s < entries; ++s)
      if (offsets[s] == o) return s;
    throw mpm::NumericalError("hypre_pfmg: Poisson entry outside the 2*dim+1-point stencil");
  };
  auto coordinates = [&](std::int64_t c) {
    IVec<dim> q;
    for (int a = 0; a < dim; ++a) {
      q[a] = static_cast<int>(c % op.cells[a]);
      c /= op.cells[a];
    }
    return q;
  };
  std::vector<double> values(static_cast<std::size_t>(n * entries), 0.0);
  const int diagonal = stencil_entry(IVec<dim>::Zero());
  for (std::int64_t c = 0; c < n; ++c)
    if (op.type[c] != CellType::fluid) values[c * entries + diagonal] = 1.0;
  op.for_each_entry([&](std::int64_t row, std::int64_t col, double v) {
    IVec<dim> o = coordinates(col) - coordinates(row);
    for (int a = 0; a < dim; ++a)  // a wrapped neighbour across a periodic face
      o[a] += o[a] > 1 ? -op.cells[a] : o[a] < -1 ? op.cells[a] : 0;
    values[row * entries + stencil_entry(o)] = v;
  });

  std::array<HYPRE_Int, dim> lower{}, upper{};
  for (int a = 0; a < dim; ++a) upper[a] = op.cells[a] - 1;
  HYPRE_StructGrid grid;
  HYPRE_StructGridCreate(MPI_COMM_WORLD, dim, &grid);
  HYPRE_StructGridSetExtents(grid, lower.data(), upper.data());
  std::array<HYPRE_Int, dim> period{};  // 0: not periodic
  for (int a = 0; a < dim; ++a) period[a] = op.periodic[a] ? op.cells[a] : 0;
  HYPRE_StructGridSetPeriodic(grid, period.data());
  HYPRE_StructGridAssemble(grid);
  HYPRE_StructStencil stencil;
  HYPRE_StructStencilCreate(dim, entries, &stencil);
  for (int s = 0; s < entries; ++s) {
    std::array<HYPRE_Int, dim> o{};
    for (int a = 0; a < dim; ++a) o[a] = offsets[s][a];
    HYPRE_StructStencilSetElement(stencil, s, o.data());
  }
  HYPRE_StructMatrix A;
  HYPRE_StructMatrixCreate(MPI_COMM_WORLD, grid, stencil, &A);
  HYPRE_StructMatrixInitialize(A);
  std::vector<HYPRE_Int> stencil_indices(static_cast<std::size_t>(entries));
  for (int s = 0; s < entries; ++s) stencil_indices[s] = s;
  HYPRE_StructMatrixSetBoxValues(A, lower.data(), upper.data(), entries, stencil_indices.data(), values.data());
  HYPRE_StructMatrixAssemble(A);
  HYPRE_StructVector hb, hx;
  HYPRE_StructVectorCreate(MPI_COMM_WORLD, grid, &hb);
  HYPRE_StructVectorCreate(MPI_COMM_WORLD, grid, &hx);
  HYPRE_StructVectorInitialize(hb);
  HYPRE_StructVectorInitialize(hx);
  std::vector<double> bx = b;
  HYPRE_StructVectorSetBoxValues(hb, lower.data(), upper.data(), bx.data());
  HYPRE_StructVectorSetBoxValues(hx, lower.data(), upper.data(), p.data());
  HYPRE_StructVectorAssemble(hb);
  HYPRE_StructVectorAssemble(hx);

  HYPRE_StructSolver solver, pfmg;
  HYPRE_StructPCGCreate(MPI_COMM_WORLD, &solver);
  HYPRE_StructPCGSetTol(solver, control.relative_tolerance);
  HYPRE_StructPCGSetAbsoluteTol(solver, control.absolute_tolerance);
  HYPRE_StructPCGSetMaxIter(solver, control.max_iterations);
  HYPRE_StructPCGSetTwoNorm(solver, 1);
  HYPRE_StructPFMGCreate(MPI_COMM_WORLD, &pfmg);
  HYPRE_StructPFMGSetMaxIter(pfmg, 1);
  HYPRE_StructPFMGSetTol(pfmg, 0.0);
  HYPRE_StructPFMGSetZeroGuess(pfmg);
  // Both smoothers give a symmetric V-cycle; hypre's red-black Gauss-Seidel (2) handles only the
  // 2*dim+1-point stencil (it overruns a fixed-size array on 3^dim points), so NodeCell uses
  // weighted Jacobi (1).
  HYPRE_StructPFMGSetRelaxType(pfmg, poisson ? 2 : 1);
  HYPRE_StructPFMGSetNumPreRelax(pfmg, 1);
  HYPRE_StructPFMGSetNumPostRelax(pfmg, 1);
  HYPRE_StructPCGSetPrecond(solver, HYPRE_StructPFMGSolve, HYPRE_StructPFMGSetup, pfmg);
  HYPRE_StructPCGSetup(solver, A, hb, hx);
  result.setup_seconds = std::chrono::duration<double>(clock::now() - start).count();
  const auto solve_start = clock::now();
  HYPRE_StructPCGSolve(solver, A, hb, hx);
  result.solve_seconds = std::chrono::duration<double>(clock::now() - solve_start).count();
  HYPRE_Int iterations = 0;
  HYPRE_StructPCGGetNumIterations(solver, &iterations);
  result.iterations = static_cast<int>(iterations);
  HYPRE_StructVectorGetBoxValues(hx, lower.data(), upper.data(), p.data());
  HYPRE_StructPFMGDestroy(pfmg);
  HYPRE_StructPCGDestroy(solver);
  HYPRE_StructVectorDestroy(hx);
  HYPRE_StructVectorDestroy(hb);
  HYPRE_StructMatrixDestroy(A);
  HYPRE_StructStencilDestroy(stencil);
  HYPRE_StructGridDestroy(grid);
  for (std::int64_t c = 0; c < n; ++c)
    if (op.type[c] != CellType::fluid) p[c] = 0.0;
  detail::measure_residual(op, b, p, control, result);
  return result;
}

template class HyprePfmgSolver<2>;
template class HyprePfmgSolver<3>;

}  // namespace fluid
