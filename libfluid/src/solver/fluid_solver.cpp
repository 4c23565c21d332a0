#include <fluid/solver/fluid_solver.h>
#include <fluid/solver/projection_solver.h>
#include <fluid/solver/weakly_compressible_solver.h>
#include <fluid/stages/implicit_viscosity.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>

namespace fluid {

std::vector<std::string> fluid_solver_names() { return {"projection", "weakly_compressible"}; }

template <int dim>
std::shared_ptr<const FluidSolver<dim>> make_fluid_solver(const FluidSolverSettings& solver, const FluidMaterial& fluid,
                                                          const stages::PressureSettings& pressure,
                                                          const mpm::geometry::ColliderSet<dim>& colliders,
                                                          const mpm::SceneSettings<dim>& settings) {
  const std::string& name = solver.name;
  const double free_surface = free_surface_wave_speed(settings, colliders);
  if (name == "projection") return std::make_shared<ProjectionSolver<dim>>(fluid, pressure, colliders, free_surface);
  if (name == "weakly_compressible") {
    MPM_VERIFY(solver.speed_of_sound > 0.0 && solver.eos_exponent >= 1.0, mpm::InputError,
               "weakly compressible fluid: speed of sound " + std::to_string(solver.speed_of_sound) +
                   " m/s and exponent " + std::to_string(solver.eos_exponent) + ": expected c > 0 and gamma >= 1");
    const TaitEquationOfState eos{fluid.density, solver.speed_of_sound, solver.eos_exponent};
    return std::make_shared<WeaklyCompressibleSolver<dim>>(
        fluid, eos, colliders, std::max(solver.speed_of_sound, free_surface), solver.hydrostatic_start);
  }
  std::string names;
  for (const std::string& n : fluid_solver_names()) names += (names.empty() ? "" : ", ") + n;
  throw mpm::InputError("unknown fluid solver '" + name + "' (solvers: " + names + ")");
}

template <int dim>
void append_viscosity(typename FluidSolver<dim>::Stages& stages, const FluidMaterial& fluid,
                      const mpm::geometry::ColliderSet<dim>& colliders) {
  if (fluid.viscosity > 0.0)
    stages.push_back(std::make_unique<stages::ImplicitViscosity<dim>>(fluid.viscosity / fluid.density, colliders,
                                                                      mpm::solve::SolveControl{1e-10, 0.0, 1000}));
}

template <int dim>
double free_surface_wave_speed(const mpm::SceneSettings<dim>& settings,
                               const mpm::geometry::ColliderSet<dim>& colliders) {
  double speed = std::sqrt(settings.gravity.norm() * settings.dx);
  // A turning collider's surface speed, bounded over the domain's diagonal.
  const double reach = (settings.domain_hi - settings.domain_lo).norm();
  for (const auto& c : colliders.colliders()) speed = std::max(speed, c.speed_within(reach));
  return speed;
}

#define FLUID_SOLVER(dim)                                                                \
  template std::shared_ptr<const FluidSolver<dim>> make_fluid_solver(                    \
      const FluidSolverSettings&, const FluidMaterial&, const stages::PressureSettings&, \
      const mpm::geometry::ColliderSet<dim>&, const mpm::SceneSettings<dim>&);           \
  template void append_viscosity<dim>(FluidSolver<dim>::Stages&, const FluidMaterial&,   \
                                      const mpm::geometry::ColliderSet<dim>&);           \
  template double free_surface_wave_speed(const mpm::SceneSettings<dim>&, const mpm::geometry::ColliderSet<dim>&);
FLUID_SOLVER(2)
FLUID_SOLVER(3)

}  // namespace fluid
