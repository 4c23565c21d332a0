#pragma once
//! Assembles an elastoplastic MPM scene from a scene file: materials, bodies (seeded
//! particles), colliders, the solid solver (`solver:`, solid_solver.h) and the staged pipeline:
//!   time_step -> sort -> [solver to_grid] -> [solver grid update] -> boundary
//!   -> [solver particle update: g2p and what follows]
//! which for the default explicit solver reads time_step -> sort -> p2g_stress (p2g with the
//! stress forces) -> grid_update -> boundary -> g2p_plasticity (g2p with the deformation update
//! and, each bucket right after its gather, the return map; g2p when every material is elastic).
//! A scene with the key `adaptive` runs on an adaptive grid (mpm/adaptive/): stage 'refine'
//! before the sort (when the grid follows the particles) and 'ghost_velocities' after the
//! boundary.
#include <mpm/adaptive/refinement.h>
#include <mpm/core/config.h>
#include <mpm/core/pipeline.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/state.h>
#include <mpm/geometry/collider.h>
#include <mpm/solid/material.h>
#include <mpm/solid/solid_solver.h>

#include <memory>

#include <cstdint>
#include <string>
#include <vector>

namespace mpm::solid {

template <int dim>
struct SolidScene {
  SceneSettings<dim> settings;
  std::vector<Material<dim>> materials;
  geometry::ColliderSet<dim> colliders;
  std::shared_ptr<const SolidSolver<dim>> solver;
  MpmState<dim> state;  //!< particles seeded (with the solver's channels), grid sized to the domain
  //! The `adaptive` key: present when state.adaptive is (refinement.h).
  std::optional<adaptive::RefinementSettings<dim>> refinement;
};

//! The "materials" list (at least one entry; names unique).
template <int dim>
std::vector<Material<dim>> parse_materials(const Config& scene);

//! Index of the material called `name`; InputError at `cfg`'s `key` when none is.
template <int dim>
std::uint16_t material_index(const std::vector<Material<dim>>& materials, const std::string& name, const Config& cfg,
                             const std::string& key);

//! Appends particles at `positions`, each of volume `volume` [m^dim] of material `m`, moving
//! with `velocity`. Every particle must lie inside the domain (InputError naming `where`). On an
//! adaptive scene the positions are the finest seeding lattice (geometry/seeding.h), and the
//! particles are regrouped to the leaves' levels (adaptive::match_particles_to_leaves).
template <int dim>
void add_particles(SolidScene<dim>& scene, const std::vector<Vec<dim>>& positions, double volume, std::uint16_t m,
                   const Vec<dim>& velocity, const std::string& where);

//! A scene with an empty particle set, the grid sized to the settings' domain and the solid
//! solver called `solver` (solid_solver_names()), with `implicit` its settings when it is
//! "implicit" (uniform grids without periodic axes only: InputError otherwise).
template <int dim>
SolidScene<dim> make_solid_scene(SceneSettings<dim> settings, std::vector<Material<dim>> materials,
                                 geometry::ColliderSet<dim> colliders, const std::string& solver = "explicit",
                                 const stages::ImplicitSettings& implicit = {});

//! Makes an unseeded scene adaptive: its AdaptiveGrid from `refinement`, the particle channel
//! "level" (mpm/adaptive/). load_solid_scene does it for the key `adaptive`.
template <int dim>
void make_adaptive(SolidScene<dim>& scene, const adaptive::RefinementSettings<dim>& refinement);

//! Apps with their own body keys: reads the scene's optional `adaptive` key
//! (adaptive::parse_refinement), refuses a static refinement beyond the memory
//! (adaptive::check_refinement_memory) and makes the unseeded scene adaptive. Size the wall
//! layer first with adaptive::levels_of: the walls act on the coarsest cells.
template <int dim>
void read_adaptive_key(SolidScene<dim>& solid, const Config& scene);

//! Seeds the optional "bodies" list of `scene` (box, sphere or mesh shapes).
template <int dim>
void seed_bodies(SolidScene<dim>& solid, const Config& scene);

//! Reads settings, materials, colliders, the solver and bodies. Apps with their own body keys build the
//! scene with make_solid_scene and add_particles instead.
template <int dim>
SolidScene<dim> load_solid_scene(const Config& scene);

//! The pipeline of the header comment for `scene` and its solver.
template <int dim>
Pipeline<MpmState<dim>> make_solid_pipeline(const SolidScene<dim>& scene);

//! Total elastic energy sum_p V_p^0 psi(F_p^E) [J].
template <int dim>
double elastic_energy(const MpmState<dim>& state, const std::vector<Material<dim>>& materials);

}  // namespace mpm::solid
