// The back-end factory: one name per class, in the order of docs/user_guide.md.
#include <fluid/pressure/cg.h>
#include <fluid/pressure/cholmod.h>
#include <fluid/pressure/hypre_boomeramg.h>
#include <fluid/pressure/hypre_pfmg.h>
#include <fluid/pressure/jacobi_pcg.h>
#include <fluid/pressure/mgpcg.h>
#include <fluid/pressure/pressure_solver.h>

#include <mpm/core/error.h>

namespace fluid {

std::vector<std::string> pressure_solver_names() {
  return {"mgpcg", "cg", "jacobi_pcg", "cholmod", "hypre_pfmg", "hypre_boomeramg"};
}

template <int dim>
std::unique_ptr<PressureSolver<dim>> make_pressure_solver(const std::string& name, int setup_reuse) {
  if (name == "mgpcg") return std::make_unique<MgpcgSolver<dim>>(setup_reuse);
  if (name == "cg") return std::make_unique<CgSolver<dim>>();
  if (name == "jacobi_pcg") return std::make_unique<JacobiPcgSolver<dim>>();
#if FLUID_WITH_CHOLMOD
  if (name == "cholmod") return std::make_unique<CholmodSolver<dim>>();
#else
  if (name == "cholmod")
    throw mpm::InputError("pressure solver 'cholmod' is not in this build (configured with SEDIMENT_WITH_CHOLMOD=OFF)");
#endif
#if FLUID_WITH_HYPRE
  if (name == "hypre_pfmg") return std::make_unique<HyprePfmgSolver<dim>>();
  if (name == "hypre_boomeramg") return std::make_unique<HypreBoomerAmgSolver<dim>>();
#else
  if (name == "hypre_pfmg" || name == "hypre_boomeramg")
    throw mpm::InputError("pressure solver '" + name +
                          "' is not in this build (configured with SEDIMENT_WITH_HYPRE=OFF)");
#endif
  std::string accepted;
  for (const std::string& n : pressure_solver_names()) accepted += (accepted.empty() ? "" : ", ") + n;
  throw mpm::InputError("unknown pressure solver '" + name + "' (accepted: " + accepted + ")");
}

template std::unique_ptr<PressureSolver<2>> make_pressure_solver<2>(const std::string&, int);
template std::unique_ptr<PressureSolver<3>> make_pressure_solver<3>(const std::string&, int);

}  // namespace fluid
