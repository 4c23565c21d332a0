#include <mpm/adaptive/particle_levels.h>
#include <mpm/adaptive/refinement.h>
#include <mpm/core/error.h>
#include <mpm/core/solve/vector_space.h>
#include <mpm/core/stages/ghost_velocities.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/refine_grid.h>
#include <mpm/core/stages/resample_particles.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/core/stages/time_step_control.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>
#include <mpm/geometry/triangle_mesh.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>
#include <mpm/solid/stages/domain_transfer.h>
#include <mpm/solid/stages/return_map.h>

#include <Eigen/Geometry>

#include <cmath>

namespace mpm::solid {

template <int dim>
std::vector<Material<dim>> parse_materials(const Config& scene) {
  std::vector<Material<dim>> materials;
  const std::vector<Config> list = scene.list("materials");
  if (list.empty()) scene.fail("materials", "at least one material is required");
  for (const Config& entry : list) {
    materials.push_back(parse_material<dim>(entry));
    for (std::size_t m = 0; m + 1 < materials.size(); ++m)
      if (materials[m].name == materials.back().name)
        entry.fail("name", "material names must be unique ('" + materials.back().name + "' repeats)");
  }
  return materials;
}

template <int dim>
std::uint16_t material_index(const std::vector<Material<dim>>& materials, const std::string& name, const Config& cfg,
                             const std::string& key) {
  std::string known;
  for (std::size_t m = 0; m < materials.size(); ++m) {
    if (materials[m].name == name) return static_cast<std::uint16_t>(m);
    known += (m ? ", " : "") + materials[m].name;
  }
  cfg.fail(key, "no material named '" + name + "' (materials: " + known + ")");
}

namespace {
//! The scene's closed walls that are no surface by its `adaptive.surface_walls`, on the lattice
//! of spacing h from `origin` (none without walls).
template <int dim>
adaptive::LatticeWalls<dim> walls_no_surface(const SolidScene<dim>& scene, const Vec<dim>& origin, double h) {
  if (!scene.colliders.walls()) return {};
  return adaptive::lattice_walls(*scene.colliders.walls(), scene.refinement->surface_walls, origin, h);
}
}  // namespace

template <int dim>
void add_particles(SolidScene<dim>& scene, const std::vector<Vec<dim>>& positions, double volume, std::uint16_t m,
                   const Vec<dim>& velocity, const std::string& where) {
  if (const OutsideDomain outside = first_outside_domain(scene.settings, positions); !outside.why.empty())
    throw InputError(where + ": " + outside.why);
  Particles<dim>& P = scene.state.particles;
  const double density = scene.materials.at(m).density;
  if (!scene.state.adaptive) {
    P.reserve_more(positions.size());
    for (const Vec<dim>& x : positions) P.push_back(x, velocity, density * volume, volume, m);
    return;
  }
  // On the finest lattice (k points per axis per cell); regrouped into coarser particles where
  // the leaves are coarse, but for the surface band.
  const int k = static_cast<int>(std::lround(std::pow(std::pow(scene.settings.dx, dim) / volume, 1.0 / dim)));
  if (k != scene.state.adaptive->points_per_axis())
    throw InputError(where + ": on an adaptive grid every body is seeded with particles_per_cell = " +
                     std::to_string(ipow(scene.state.adaptive->points_per_axis(), dim)) + " (" +
                     std::to_string(scene.state.adaptive->points_per_axis()) + " per axis), so that the particles' " +
                     "boxes tile the body across levels");
  const int surface_steps = static_cast<int>(std::ceil(scene.refinement->surface_band * k / scene.settings.dx));
  const auto levelled = adaptive::match_particles_to_leaves(
      scene.state.adaptive->tree(), positions, volume, k, surface_steps,
      walls_no_surface<dim>(scene, Vec<dim>::Zero(), scene.settings.dx / k));  // the seeding lattice, (i + 1/2) dx / k
  P.reserve_more(levelled.x.size());
  std::vector<std::uint16_t>& level = P.template channel<std::uint16_t>(adaptive::kParticleLevel);
  for (std::size_t i = 0; i < levelled.x.size(); ++i) {
    P.push_back(levelled.x[i], velocity, density * levelled.volume[i], levelled.volume[i], m);
    level.back() = levelled.level[i];
  }
}

template <int dim>
void make_adaptive(SolidScene<dim>& scene, const adaptive::RefinementSettings<dim>& refinement) {
  MPM_VERIFY(scene.state.particles.size() == 0, InputError, "a scene becomes adaptive before it is seeded");
  scene.refinement = refinement;
  scene.state.adaptive.emplace(adaptive::build_tree(refinement, scene.settings, scene.colliders));
  adaptive::add_level_channel(scene.state.particles, scene.state.adaptive->tree());
}

namespace {
//! A 3D body seeded from a triangle mesh (shape: level_set, file .obj/.stl) carries that mesh
//! embedded in its domains (Zhu et al. sec. 4.1), written per frame as mesh_NNNN.h5: a smooth
//! surface where the domains' own boundary is stepped at the particle spacing. The file is read
//! a second time here (the level-set loader, which checked it closed, keeps only the grid).
template <int dim>
void embed_seeding_mesh(domains::ParticleDomains<dim>& d, std::size_t first, const std::vector<Vec<dim>>& x,
                        double spacing, const Config& body) {
  if constexpr (dim == 3) {
    if (body.text("shape", "box") != "level_set" || !geometry::is_triangle_mesh_file(body.text("file"))) return;
    const geometry::TriangleMesh mesh = geometry::read_triangle_mesh(body.input_file("file").string());
    std::vector<std::array<std::uint32_t, 3>> triangles;
    triangles.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles)
      triangles.push_back(
          {static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]), static_cast<std::uint32_t>(t[2])});
    try {
      domains::embed_mesh<dim>(d, first, x, spacing, mesh.vertices, triangles);
    } catch (const Error& e) {
      body.fail("file", e.what());
    }
  }
}

template <int dim>
void seed_body(SolidScene<dim>& scene, const Config& body) {
  const geometry::BodyParticles<dim> body_particles = geometry::seed_body_shape<dim>(body, scene.settings);
  const std::vector<Vec<dim>>& x = body_particles.x;
  const std::uint16_t m = material_index(scene.materials, body.text("material"), body, "material");
  const Vec<dim> velocity = body.vector<dim>("velocity", Vec<dim>::Zero());
  // A body may start deformed, F = diag(stretch), from a rest state of volume V / |det F| (a
  // crushed or inverted block), and spinning rigidly about its centroid.
  const Vec<dim> stretch = body.vector<dim>("stretch", Vec<dim>::Ones());
  if (!(stretch.array().abs() > 0.0).all()) body.fail("stretch", "every component must be nonzero");
  const std::size_t first = scene.state.particles.size();
  Particles<dim>& P = scene.state.particles;
  add_particles(scene, x, body_particles.volume, m, velocity, body.path());
  // The domains are the cells of the seeding lattice; a plastic body runs among them as
  // material points (particle_domains.h).
  const bool elastic = std::holds_alternative<plasticity::NoPlasticity>(scene.materials.at(m).plasticity);
  if (!scene.state.domains && body.has("domains"))
    body.fail("domains", "chooses domains or material points in a scene with particle_domains: true");
  if (scene.state.domains && body.flag("domains", elastic)) {
    if (!elastic)
      body.fail("domains", "a body with particle domains needs an elastic material ('" + scene.materials.at(m).name +
                               "' is plastic): set domains: false to run it as material points");
    if (body.number("jitter", 0.0, Range::any()) != 0.0)
      body.fail("jitter", "particle_domains need particles on the seeding lattice: jitter must be 0");
    const double spacing = std::pow(body_particles.volume, 1.0 / dim);  // of the seeding lattice
    domains::add_body(*scene.state.domains, first, x, spacing, stretch);
    embed_seeding_mesh(*scene.state.domains, first, x, spacing, body);
  } else if (scene.state.domains) {
    domains::add_points(*scene.state.domains, first, x);
  }
  for (std::size_t p = first; p < P.size(); ++p) {  // the rest state of a stretched body
    P.volume0[p] /= std::fabs(stretch.prod());
    P.mass[p] = scene.materials.at(m).density * P.volume0[p];
  }
  Vec<dim> centroid = Vec<dim>::Zero();
  for (const Vec<dim>& p : x) centroid += p / static_cast<double>(x.size());
  Eigen::Matrix<double, 3, 1> omega = Eigen::Matrix<double, 3, 1>::Zero();
  if constexpr (dim == 2)
    omega[2] = body.number("angular_velocity", 0.0, Range::any());
  else
    omega = body.vector<3>("angular_velocity", Vec<3>::Zero());
  // Only a solver that tracks deformation (explicit) carries F; stress-free grains start at rest.
  std::vector<Mat<dim>>* F = P.template find_channel<Mat<dim>>(kElasticF);
  if (!F && stretch != Vec<dim>::Ones())
    body.fail("stretch", "a stretched body needs a solver that tracks deformation (solver: explicit)");
  // A dilatant sand's grains start at the body's packing fraction (without the key: critical).
  if (body.has("packing_fraction")) {
    const auto* sand = std::get_if<plasticity::DruckerPrager<dim>>(&scene.materials.at(m).plasticity);
    if (!sand || !sand->dilatant())
      body.fail("packing_fraction", "a packing fraction needs a dilatant material (plasticity.dilatancy > 0)");
    const double phi = body.number("packing_fraction", Range::open(0.0, 1.0));
    std::vector<double>* packing = rest_packing(P);  // declared by the explicit solver
    if (!packing) body.fail("packing_fraction", "a packing fraction needs solver: explicit");
    for (std::size_t p = first; p < P.size(); ++p) (*packing)[p] = phi * std::fabs(stretch.prod());
  }
  for (std::size_t p = first; p < P.size(); ++p) {
    if (F) (*F)[p] = stretch.asDiagonal();
    Eigen::Matrix<double, 3, 1> r = Eigen::Matrix<double, 3, 1>::Zero();
    r.template head<dim>() = P.x[p] - centroid;
    P.v[p] += omega.cross(r).template head<dim>();
  }
}
}  // namespace

template <int dim>
SolidScene<dim> make_solid_scene(SceneSettings<dim> settings, std::vector<Material<dim>> materials,
                                 geometry::ColliderSet<dim> colliders, const std::string& solver,
                                 const stages::ImplicitSettings& implicit) {
  for (int a = 0; solver == "implicit" && a < dim; ++a)
    MPM_VERIFY(!settings.periodic[a], InputError, "solver 'implicit' does not support periodic axes yet");
  MpmState<dim> state = initial_state(settings);
  // The solver declares its channels before seeding, even for a scene without bodies: its
  // stages read them, and a restart loads them into this particle set.
  std::shared_ptr<const SolidSolver<dim>> s = make_solid_solver<dim>(solver, materials, false, colliders, implicit);
  s->add_channels(state.particles);
  return {std::move(settings), std::move(materials), std::move(colliders), std::move(s), std::move(state), {}};
}

template <int dim>
void read_adaptive_key(SolidScene<dim>& solid, const Config& scene) {
  if (const auto refinement = adaptive::parse_refinement<dim>(scene, solid.settings)) {
    adaptive::check_refinement_memory(scene, *refinement, solid.settings, solid.colliders);
    make_adaptive(solid, *refinement);
  }
}

template <int dim>
void seed_bodies(SolidScene<dim>& solid, const Config& scene) {
  for (const Config& body : scene.list("bodies")) seed_body(solid, body);
}

namespace {
//! The scenes particle domains support (particle_domains.h): explicit or implicit, on a
//! uniform, non-periodic grid with the PIC/FLIP transfer of Zhu et al. (bodies: seed_body).
template <int dim>
void check_particle_domains(const SolidScene<dim>& s, const Config& scene) {
  const std::string why = "particle_domains: true needs ";
  if (s.solver->name() != "explicit" && s.solver->name() != "implicit")
    scene.fail("particle_domains", why + "solver: explicit or implicit (solver is '" + s.solver->name() + "')");
  if (s.state.adaptive) scene.fail("particle_domains", why + "a uniform grid (remove the key 'adaptive')");
  for (int a = 0; a < dim; ++a)
    if (s.settings.periodic[a]) scene.fail("particle_domains", why + "walls on every axis (no periodic axis)");
  if (s.settings.transfer.type != TransferScheme::Type::flip)
    scene.fail("particle_domains", why + "transfer.scheme: flip (the domains blend PIC and FLIP; flip_ratio 0 is PIC)");
}
}  // namespace

//! domain_contact: the thickness of the enriched surfaces' self-contact (surface_contact.h) as a
//! fraction of the smallest domain's rest side; on by default where an explicit step enriches
//! domains. The implicit step has none: impulses after its solve would move the corners off
//! the solved state (tried: the enriched funnel squeeze then gains energy, 11.7 S).
template <int dim>
void read_domain_contact(domains::ParticleDomains<dim>& d, const Config& scene, const std::string& solver) {
  if (d.enrichment_threshold <= 0.0) {
    if (scene.has("domain_contact"))
      scene.fail("domain_contact", "is the self-contact of enriched domains: it needs domain_enrichment");
    return;
  }
  if (solver == "implicit") {
    if (scene.has("domain_contact"))
      scene.fail("domain_contact", "acts in the explicit step only (solver 'implicit' has no self-contact)");
    return;
  }
  const double fraction = scene.number("domain_contact", 0.2, Range::half_open(0.0, 1.0));
  double side = std::numeric_limits<double>::infinity();
  for (std::size_t p = 0; p < d.particle_count(); ++p)
    if (!d.is_point(p)) side = std::min(side, 1.0 / d.inverse_side[p].cwiseAbs().maxCoeff());
  d.contact_thickness = std::isfinite(side) ? fraction * side : 0.0;
}

template <int dim>
SolidScene<dim> load_solid_scene(const Config& scene) {
  SceneSettings<dim> settings = parse_scene_settings<dim>(scene);
  // Walls act on the nodes within two cells of the faces: of coarse cells on an adaptive grid.
  const double wall_dx = settings.dx * (1 << (adaptive::levels_of(scene) - 1));
  auto colliders = geometry::parse_colliders<dim>(scene, settings.domain_lo, settings.domain_hi,
                                                  wall_layer(settings.kernel, wall_dx));
  const std::string solver = scene.choice("solver", "explicit", solid_solver_names());
  const stages::ImplicitSettings implicit = parse_implicit_settings(scene, solver);
  if (solver == "implicit" && scene.has("adaptive"))
    scene.fail("solver", "solver 'implicit' runs on a uniform grid only; remove the key 'adaptive' or use 'explicit'");
  for (int a = 0; solver == "implicit" && a < dim; ++a)
    if (settings.periodic[a]) scene.fail("solver", "solver 'implicit' does not support periodic axes yet");
  SolidScene<dim> s =
      make_solid_scene(std::move(settings), parse_materials<dim>(scene), std::move(colliders), solver, implicit);
  read_adaptive_key(s, scene);
  if (scene.flag("particle_domains", false)) {
    check_particle_domains(s, scene);
    s.state.domains.emplace();
    // Dynamic enrichment (Zhu et al. sec. 5): epsilon of K(F) <= epsilon; the paper uses 0.6.
    if (scene.has("domain_enrichment"))
      s.state.domains->enrichment_threshold = scene.number("domain_enrichment", Range::open(0.0, 1.0));
  } else if (scene.has("domain_enrichment")) {
    scene.fail("domain_enrichment", "enriches particle domains: it needs particle_domains: true");
  }
  seed_bodies(s, scene);
  if (s.state.domains) {
    domains::index_sharing(*s.state.domains);
    read_domain_contact(*s.state.domains, scene, solver);
    if (solver == "implicit" && s.state.domains->point_count)
      scene.fail("solver", "solver 'implicit' with particle_domains needs domains on every body (" +
                               std::to_string(s.state.domains->point_count) + " particles are material points)");
  }
  return s;
}

template <int dim>
Pipeline<MpmState<dim>> make_solid_pipeline(const SolidScene<dim>& scene) {
  Pipeline<MpmState<dim>> p(particle_fields(scene.state.particles));
  if (scene.refinement && scene.refinement->resample) {
    std::vector<std::string> deformation;
    if (scene.state.particles.has_channel(kElasticF)) deformation.push_back(kElasticF);
    const adaptive::CellTree<dim>& tree = scene.state.adaptive->tree();  // its finest cells
    p.add(std::make_unique<stages::ResampleParticles<dim>>(
        *scene.refinement->resample, deformation, walls_no_surface(scene, tree.origin(), tree.dx(tree.finest()))));
  }
  // Enrichment first: the time step needs the thinnest enriched domain (explicit steps only: an
  // implicit step solves the enriched corners too).
  const bool implicit = scene.solver->name() == "implicit";
  if (scene.state.domains && scene.state.domains->enrichment_threshold > 0.0)
    p.add(std::make_unique<stages::DomainEnrichment<dim>>(!implicit));
  // A solver stable at any step (implicit, grains) still resolves free fall: a particle at
  // rest falls at most wave_cfl^2 dx / 2 in its first step, dt <= wave_cfl sqrt(dx / |g|).
  double wave_speed = scene.solver->wave_speed();
  if (wave_speed == 0.0) wave_speed = std::sqrt(scene.settings.gravity.norm() * scene.settings.dx);
  auto dt_settings = stages::time_step_settings(scene.settings, wave_speed);
  dt_settings.bound_enriched = !implicit;
  p.add(std::make_unique<stages::TimeStepControl<dim>>(dt_settings));
  if (scene.refinement && scene.refinement->follow_particles)
    p.add(std::make_unique<stages::RefineGrid<dim>>(
        adaptive::build_tree(*scene.refinement, scene.settings, scene.colliders), scene.refinement->padding));
  // Particle domains replace sort, p2g, the explicit stress forces and g2p (with the deformation
  // update) by the two transfers through the corners (domain_transfer.h).
  if (scene.state.domains) {
    p.add(std::make_unique<stages::DomainsToGrid<dim>>(scene.materials, !implicit));
    if (implicit)
      for (auto& stage : scene.solver->grid_update()) p.add(std::move(stage));
    else
      p.add(std::make_unique<stages::GridVelocityUpdate<dim>>(true));
  } else {
    p.add(std::make_unique<stages::SortParticles<dim>>());
    for (auto& stage : scene.solver->to_grid()) p.add(std::move(stage));
    for (auto& stage : scene.solver->grid_update()) p.add(std::move(stage));
  }
  p.add(std::make_unique<stages::GridBoundary<dim>>(scene.colliders));
  if (scene.state.adaptive) p.add(std::make_unique<stages::GhostVelocities<dim>>());
  if (scene.state.domains) {
    p.add(std::make_unique<stages::DomainsFromGrid<dim>>(scene.colliders, implicit,
                                                         scene.state.domains->contact_thickness > 0.0));
    if (stages::any_plastic(scene.materials))  // the material points' (bodies with domains are elastic)
      p.add(std::make_unique<stages::ReturnMap<dim>>(scene.materials));
  } else {
    for (auto& stage : scene.solver->particle_update()) p.add(std::move(stage));
  }
  return p;
}

template <int dim>
double elastic_energy(const MpmState<dim>& state, const std::vector<Material<dim>>& materials) {
  const Particles<dim>& P = state.particles;
  const std::vector<Mat<dim>>* F = P.template find_channel<Mat<dim>>(kElasticF);
  if (!F) return 0.0;  // stress-free grains store no elastic energy
  const std::vector<double>& plastic = plastic_state(P);
  // In parallel: one SVD per particle, 0.18 s per frame per million particles in one thread.
  return solve::sum_by_blocks(P.size(), [&](std::size_t first, std::size_t last) {
    double e = 0.0;
    for (std::size_t p = first; p < last; ++p) e += P.volume0[p] * materials[P.material[p]].energy((*F)[p], plastic[p]);
    return e;
  });
}

#define MPM_SOLID_SCENE(dim)                                                                                          \
  template std::vector<Material<dim>> parse_materials<dim>(const Config&);                                            \
  template std::uint16_t material_index(const std::vector<Material<dim>>&, const std::string&, const Config&,         \
                                        const std::string&);                                                          \
  template void add_particles(SolidScene<dim>&, const std::vector<Vec<dim>>&, double, std::uint16_t, const Vec<dim>&, \
                              const std::string&);                                                                    \
  template SolidScene<dim> make_solid_scene(SceneSettings<dim>, std::vector<Material<dim>>,                           \
                                            geometry::ColliderSet<dim>, const std::string&,                           \
                                            const stages::ImplicitSettings&);                                         \
  template void make_adaptive(SolidScene<dim>&, const adaptive::RefinementSettings<dim>&);                            \
  template void read_adaptive_key(SolidScene<dim>&, const Config&);                                                   \
  template void seed_bodies(SolidScene<dim>&, const Config&);                                                         \
  template SolidScene<dim> load_solid_scene<dim>(const Config&);                                                      \
  template Pipeline<MpmState<dim>> make_solid_pipeline(const SolidScene<dim>&);                                       \
  template double elastic_energy(const MpmState<dim>&, const std::vector<Material<dim>>&);
MPM_SOLID_SCENE(2)
MPM_SOLID_SCENE(3)

}  // namespace mpm::solid
