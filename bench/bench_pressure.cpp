// bench_pressure: every pressure back-end on the same systems, in one run.
//  (a) the standard 2*dim+1-point Poisson problem (p = 0 outside the box: Dirichlet walls),
//      every cell fluid;
//  (b) the project's node/cell operator on the dam-break domain (water in the lower-left
//      quarter, walls, free surface; fluid::dam_break_problem).
// The right-hand side is b = -D u for a pseudo-random wall-consistent nodal velocity u.
// For each problem and size it prints setup and solve seconds, iterations, the true relative
// residual and the solve time relative to mgpcg. Thread count 1 by default (tbb::global_control).
//
//   bench_pressure          (Poisson 64^3, 128^3, 256^2, 1024^2; dam break 32^3, 64^3, 256^2, 1024^2)
//   bench_pressure --poisson-3d 32 --poisson-2d 256 --dam-break-3d 16 --dam-break-2d 256
//                  --solvers mgpcg,hypre_pfmg            (quick; one command line)
#include <fluid/pressure/model_problems.h>
#include <fluid/pressure/pressure_solver.h>

#include <mpm/core/memory_budget.h>

#include <tbb/global_control.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

using namespace fluid;

namespace {

struct Options {
  std::vector<int> poisson_3d{64, 128}, poisson_2d{256, 1024};
  std::vector<int> dam_break_3d{32, 64}, dam_break_2d{256, 1024};
  std::vector<std::string> solvers = pressure_solver_names();
  int max_cholmod_cells = 70000;  //!< skip the direct solver above this many fluid cells (3D fill-in)
  int max_cg_cells = 300000;      //!< skip unpreconditioned CG above this many fluid cells (time)
  double rtol = 1e-8;
  int threads = 1;
};

//! Peak bytes per cell of a run (the operator, the vectors, the multigrid levels), from measured
//! mgpcg peaks with a margin: Poisson 113-114 B (128^3, 2048^2), dam break 175 B (1024^2) and
//! 1 130-1 160 B (64^3, 96^3; the node/cell operator's Galerkin levels).
double bytes_per_cell(int dim, const std::string& problem) {
  if (problem == "poisson") return 160.0;
  return dim == 2 ? 250.0 : 1600.0;
}

//! "" when every requested system fits in memory, else the first that does not and why.
std::string memory_refusal(const Options& o) {
  const auto check = [](const char* option, int dim, const std::string& problem, const std::vector<int>& sizes) {
    for (const int n : sizes) {
      const double cells = std::pow(double(n), dim);
      if (const std::string why = mpm::memory_shortfall(cells * bytes_per_cell(dim, problem)); !why.empty())
        return std::string(option) + " " + std::to_string(n) + ": " + std::to_string(static_cast<long long>(cells)) +
               " cells need " + why;
    }
    return std::string();
  };
  for (const std::string& why :
       {check("--poisson-3d", 3, "poisson", o.poisson_3d), check("--poisson-2d", 2, "poisson", o.poisson_2d),
        check("--dam-break-3d", 3, "dam_break", o.dam_break_3d),
        check("--dam-break-2d", 2, "dam_break", o.dam_break_2d)})
    if (!why.empty()) return why;
  return {};
}

template <int dim>
void run(const Options& options, const std::string& problem, int n) {
  const auto kind = problem == "poisson" ? OperatorKind<dim>::poisson : OperatorKind<dim>::node_cell;
  const CellOperator<dim> op =
      problem == "poisson" ? closed_box_problem<dim>(n, kind) : dam_break_problem<dim>(n, kind);
  std::vector<double> b;
  op.divergence(wall_consistent_velocity<dim>(op, 1), b);
  SolveControl control;
  control.relative_tolerance = options.rtol;
  control.max_iterations = 5000;
  const auto fluid = std::count(op.type.begin(), op.type.end(), CellType::fluid);
  std::printf("\n%s %dD %d^%d (%lld cells, %lld fluid)\n", problem.c_str(), dim, n, dim,
              static_cast<long long>(op.cell_count()), static_cast<long long>(fluid));
  std::printf("  %-16s %9s %9s %6s %10s %10s %s\n", "solver", "setup s", "solve s", "iters", "rel.res", "solve/mg", "");
  double mg_solve = 0.0;
  for (const std::string& name : options.solvers) {
    if ((name == "cholmod" && fluid > options.max_cholmod_cells) || (name == "cg" && fluid > options.max_cg_cells)) {
      std::printf("  %-16s skipped (more than the --max-%s-cells limit)\n", name.c_str(), name.c_str());
      continue;
    }
    std::vector<double> p;
    const SolveResult r = make_pressure_solver<dim>(name)->solve(op, b, p, control);
    if (name == "mgpcg") mg_solve = r.solve_seconds;
    std::printf("  %-16s %9.3f %9.3f %6d %10.2e %10.2f %s\n", name.c_str(), r.setup_seconds, r.solve_seconds,
                r.iterations, r.relative_residual, mg_solve > 0.0 ? r.solve_seconds / mg_solve : 0.0,
                r.converged ? "" : "NOT CONVERGED");
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  CLI::App app{"bench_pressure: pressure solver back-ends on the Poisson and dam-break systems"};
  const auto sizes = CLI::Range(2, 65536);
  app.add_option("--poisson-3d", options.poisson_3d, "cells per axis, 3D Poisson runs")->delimiter(',')->check(sizes);
  app.add_option("--poisson-2d", options.poisson_2d, "cells per axis, 2D Poisson runs")->delimiter(',')->check(sizes);
  app.add_option("--dam-break-3d", options.dam_break_3d, "cells per axis, 3D dam-break runs")
      ->delimiter(',')
      ->check(sizes);
  app.add_option("--dam-break-2d", options.dam_break_2d, "cells per axis, 2D dam-break runs")
      ->delimiter(',')
      ->check(sizes);
  app.add_option("--solvers", options.solvers, "back-ends, mgpcg first for the ratio column")
      ->delimiter(',')
      ->check(CLI::IsMember(pressure_solver_names()));
  app.add_option("--max-cholmod-cells", options.max_cholmod_cells, "largest system for cholmod")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-cg-cells", options.max_cg_cells, "largest system for plain cg")->check(CLI::NonNegativeNumber);
  app.add_option("--rtol", options.rtol, "relative residual tolerance, in [1e-16, 0.5]")
      ->check(CLI::Validator(
          [](const std::string& text) {
            const double value = std::strtod(text.c_str(), nullptr);
            return value >= 1e-16 && value <= 0.5 ? std::string() : "value " + text + " not in [1e-16, 0.5]";
          },
          "in [1e-16, 0.5]"));
  app.add_option("--threads", options.threads, "TBB threads (the targets are for 1)")
      ->check(CLI::Range(1, cores, "thread count in [1, cores of this machine = " + std::to_string(cores) + "]"));
  CLI11_PARSE(app, argc, argv);
  if (const std::string why = memory_refusal(options); !why.empty()) {
    std::fprintf(stderr, "bench_pressure: %s\n", why.c_str());
    return 2;
  }
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(options.threads));
  std::printf("bench_pressure: rtol %.1e, %d thread(s)\n", options.rtol, options.threads);
  for (int n : options.poisson_3d) run<3>(options, "poisson", n);
  for (int n : options.poisson_2d) run<2>(options, "poisson", n);
  for (int n : options.dam_break_3d) run<3>(options, "dam_break", n);
  for (int n : options.dam_break_2d) run<2>(options, "dam_break", n);
  return 0;
}
