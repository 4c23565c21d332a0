#include <mpm/solid/explicit_solver.h>
#include <mpm/solid/solid_solver.h>

#include <mpm/core/error.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/solid/stages/deformation_update.h>
#include <mpm/solid/stages/return_map.h>
#include <mpm/solid/stages/stress_forces.h>

#include <algorithm>

namespace mpm::solid {

std::vector<std::string> solid_solver_names() { return {"explicit", "grains"}; }

template <int dim>
std::shared_ptr<const SolidSolver<dim>> make_solid_solver(const std::string& name, std::vector<Material<dim>> materials,
                                                          bool stress_free_particles) {
  if (name == "grains") return std::make_shared<GrainSolver<dim>>();
  if (name == "explicit") {
    MPM_VERIFY(!materials.empty(), InputError, "solid solver 'explicit' needs at least one material");
    return std::make_shared<ExplicitSolver<dim>>(std::move(materials), stress_free_particles);
  }
  std::string names;
  for (const std::string& n : solid_solver_names()) names += (names.empty() ? "" : ", ") + n;
  throw InputError("unknown solid solver '" + name + "' (solvers: " + names + ")");
}

template <int dim>
ExplicitSolver<dim>::ExplicitSolver(std::vector<Material<dim>> materials, bool stress_free_particles)
    : materials_(std::move(materials)), stress_free_particles_(stress_free_particles) {}

template <int dim>
double ExplicitSolver<dim>::wave_speed() const {
  double c = 0.0;
  for (const Material<dim>& m : materials_) c = std::max(c, m.wave_speed());
  return c;
}

template <int dim>
typename ExplicitSolver<dim>::Stages ExplicitSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::StressForces<dim>>(materials_, stress_free_particles_));
  s.push_back(std::make_unique<stages::GridVelocityUpdate<dim>>(true));
  return s;
}

template <int dim>
typename ExplicitSolver<dim>::Stages ExplicitSolver<dim>::particle_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::DeformationUpdate<dim>>());
  if (stages::any_plastic(materials_)) s.push_back(std::make_unique<stages::ReturnMap<dim>>(materials_));
  return s;
}

template <int dim>
typename GrainSolver<dim>::Stages GrainSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::GridVelocityUpdate<dim>>(false));
  return s;
}

template std::shared_ptr<const SolidSolver<2>> make_solid_solver(const std::string&, std::vector<Material<2>>, bool);
template std::shared_ptr<const SolidSolver<3>> make_solid_solver(const std::string&, std::vector<Material<3>>, bool);
template class ExplicitSolver<2>;
template class ExplicitSolver<3>;
template class GrainSolver<2>;
template class GrainSolver<3>;

}  // namespace mpm::solid
