#include <fluid/solver/fluid_solver.h>
#include <fluid/solver/projection_solver.h>

#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>

namespace fluid {

std::vector<std::string> fluid_solver_names() { return {"projection"}; }

template <int dim>
std::shared_ptr<const FluidSolver<dim>> make_fluid_solver(const std::string& name, const FluidMaterial& fluid,
                                                          const stages::PressureSettings& pressure,
                                                          const mpm::geometry::ColliderSet<dim>& colliders,
                                                          const mpm::SceneSettings<dim>& settings) {
  if (name == "projection")
    return std::make_shared<ProjectionSolver<dim>>(fluid, pressure, colliders,
                                                   free_surface_wave_speed(settings, colliders));
  std::string names;
  for (const std::string& n : fluid_solver_names()) names += (names.empty() ? "" : ", ") + n;
  throw mpm::InputError("unknown fluid solver '" + name + "' (solvers: " + names + ")");
}

template <int dim>
double free_surface_wave_speed(const mpm::SceneSettings<dim>& settings, const mpm::geometry::ColliderSet<dim>& colliders) {
  double speed = std::sqrt(settings.gravity.norm() * settings.dx);
  for (const auto& c : colliders.colliders()) speed = std::max(speed, c.velocity().norm());
  return speed;
}

#define FLUID_SOLVER(dim)                                                                                          \
  template std::shared_ptr<const FluidSolver<dim>> make_fluid_solver(                                              \
      const std::string&, const FluidMaterial&, const stages::PressureSettings&,                                   \
      const mpm::geometry::ColliderSet<dim>&, const mpm::SceneSettings<dim>&);                                     \
  template double free_surface_wave_speed(const mpm::SceneSettings<dim>&, const mpm::geometry::ColliderSet<dim>&);
FLUID_SOLVER(2)
FLUID_SOLVER(3)

}  // namespace fluid
