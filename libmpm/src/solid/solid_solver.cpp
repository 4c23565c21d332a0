#include <mpm/solid/explicit_solver.h>
#include <mpm/solid/implicit_solver.h>
#include <mpm/solid/solid_solver.h>

#include <mpm/core/error.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/solid/stages/return_map.h>
#include <mpm/solid/stages/stress_forces.h>

#include <algorithm>

namespace mpm::solid {

std::vector<std::string> solid_solver_names() { return {"explicit", "implicit", "grains"}; }

template <int dim>
std::shared_ptr<const SolidSolver<dim>> make_solid_solver(const std::string& name, std::vector<Material<dim>> materials,
                                                          bool stress_free_particles,
                                                          geometry::ColliderSet<dim> colliders,
                                                          const stages::ImplicitSettings& implicit) {
  if (name == "grains") return std::make_shared<GrainSolver<dim>>();
  MPM_VERIFY((name != "explicit" && name != "implicit") || !materials.empty(), InputError,
             "solid solver '" + name + "' needs at least one material");
  if (name == "explicit") return std::make_shared<ExplicitSolver<dim>>(std::move(materials), stress_free_particles);
  MPM_VERIFY(name != "implicit" || !stages::any_dilatant(materials), InputError,
             "solid solver 'implicit' does not support dilatant sand yet (plasticity.dilatancy > 0): use "
             "solver: explicit");
  if (name == "implicit")
    return std::make_shared<ImplicitSolver<dim>>(std::move(materials), std::move(colliders), implicit);
  std::string names;
  for (const std::string& n : solid_solver_names()) names += (names.empty() ? "" : ", ") + n;
  throw InputError("unknown solid solver '" + name + "' (solvers: " + names + ")");
}

stages::ImplicitSettings parse_implicit_settings(const Config& parent, const std::string& solver) {
  stages::ImplicitSettings s;
  const std::optional<Config> keys = parent.optional_child("implicit");
  if (!keys) return s;
  if (solver != "implicit")
    parent.fail("implicit", "the implicit solve settings need solver: implicit (solver is '" + solver + "')");
  s.tolerance = keys->number("tolerance", s.tolerance, Range::positive());
  s.max_newton_iterations = keys->integer("max_newton_iterations", s.max_newton_iterations, 1, 1000);
  s.linear_tolerance = keys->number("linear_tolerance", s.linear_tolerance, Range::open(0.0, 1.0));
  s.max_linear_iterations = keys->integer("max_linear_iterations", s.max_linear_iterations, 1, 1000000);
  s.on_failure =
      keys->choice("on_failure", "stop", {"stop", "warn"}) == "stop" ? solve::OnFailure::stop : solve::OnFailure::warn;
  return s;
}

template <int dim>
typename SolidSolver<dim>::Stages SolidSolver<dim>::to_grid() const {
  Stages s;
  s.push_back(std::make_unique<stages::ParticlesToGrid<dim>>());
  return s;
}

namespace {
//! g2p with the deformation update and, where a material is plastic, the return map of each
//! bucket right after its gather: the particle update of both elastoplastic solvers.
template <int dim>
typename SolidSolver<dim>::Stages elastoplastic_particle_update(const std::vector<Material<dim>>& materials) {
  typename SolidSolver<dim>::Stages s;
  std::unique_ptr<stages::ParticleStage<dim>> plasticity;
  if (stages::any_plastic(materials)) plasticity = std::make_unique<stages::ReturnMap<dim>>(materials);
  s.push_back(std::make_unique<stages::GridToParticles<dim>>(kElasticF, std::move(plasticity)));
  return s;
}
}  // namespace

template <int dim>
ExplicitSolver<dim>::ExplicitSolver(std::vector<Material<dim>> materials, bool stress_free_particles)
    : materials_(std::move(materials)), stress_free_particles_(stress_free_particles) {}

template <int dim>
void ExplicitSolver<dim>::add_channels(Particles<dim>& particles) const {
  add_solid_channels(particles);
  if (stages::any_plastic(materials_)) add_stress_cache(particles);
  if (stages::any_dilatant(materials_)) add_rest_packing(particles);
}

template <int dim>
double ExplicitSolver<dim>::wave_speed() const {
  double c = 0.0;
  for (const Material<dim>& m : materials_) c = std::max(c, m.wave_speed());
  return c;
}

template <int dim>
typename ExplicitSolver<dim>::Stages ExplicitSolver<dim>::to_grid() const {
  Stages s;
  s.push_back(std::make_unique<stages::StressForces<dim>>(materials_, stress_free_particles_,
                                                          stages::StressForces<dim>::Scatter::with_momentum));
  return s;
}

template <int dim>
typename ExplicitSolver<dim>::Stages ExplicitSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::GridVelocityUpdate<dim>>(true));
  return s;
}

template <int dim>
typename ExplicitSolver<dim>::Stages ExplicitSolver<dim>::particle_update() const {
  return elastoplastic_particle_update(materials_);
}

template <int dim>
ImplicitSolver<dim>::ImplicitSolver(std::vector<Material<dim>> materials, geometry::ColliderSet<dim> colliders,
                                    stages::ImplicitSettings settings)
    : materials_(std::move(materials)), colliders_(std::move(colliders)), settings_(settings) {}

template <int dim>
typename ImplicitSolver<dim>::Stages ImplicitSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::ImplicitUpdate<dim>>(materials_, colliders_, settings_));
  return s;
}

template <int dim>
typename ImplicitSolver<dim>::Stages ImplicitSolver<dim>::particle_update() const {
  return elastoplastic_particle_update(materials_);
}

template <int dim>
typename GrainSolver<dim>::Stages GrainSolver<dim>::particle_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::GridToParticles<dim>>());
  return s;
}

template <int dim>
typename GrainSolver<dim>::Stages GrainSolver<dim>::grid_update() const {
  Stages s;
  s.push_back(std::make_unique<stages::GridVelocityUpdate<dim>>(false));
  return s;
}

template std::shared_ptr<const SolidSolver<2>> make_solid_solver(const std::string&, std::vector<Material<2>>, bool,
                                                                 geometry::ColliderSet<2>,
                                                                 const stages::ImplicitSettings&);
template std::shared_ptr<const SolidSolver<3>> make_solid_solver(const std::string&, std::vector<Material<3>>, bool,
                                                                 geometry::ColliderSet<3>,
                                                                 const stages::ImplicitSettings&);
template class SolidSolver<2>;
template class SolidSolver<3>;
template class ExplicitSolver<2>;
template class ExplicitSolver<3>;
template class ImplicitSolver<2>;
template class ImplicitSolver<3>;
template class GrainSolver<2>;
template class GrainSolver<3>;

}  // namespace mpm::solid
