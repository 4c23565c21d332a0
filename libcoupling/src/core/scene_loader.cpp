#include <coupling/scene_loader.h>
#include <coupling/stages/reclassify_sediment.h>
#include <mpm/core/error.h>
#include <mpm/core/number_text.h>
#include <mpm/geometry/body_config.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/solid_channels.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <unordered_set>
#include <vector>

namespace coupling {

namespace {

//! The pores of one sediment body: the sub-cells of its seeding lattice (spacing dx / k,
//! seeding.h) that hold one of its particles. Jitter keeps a particle inside its sub-cell, so
//! a point lies in the body (to the lattice's resolution) when its sub-cell is listed.
template <int dim>
class Pores {
public:
  Pores(const std::vector<mpm::Vec<dim>>& grains, double spacing, double packing)
      : spacing_(spacing), packing_(packing) {
    for (const mpm::Vec<dim>& x : grains) cells_.insert(key(x));
  }
  bool contain(const mpm::Vec<dim>& x) const { return cells_.count(key(x)) > 0; }
  double packing() const { return packing_; }

private:
  // 21 bits per axis, offset so that negative sub-cells pack too (2^20 sub-cells each way).
  std::uint64_t key(const mpm::Vec<dim>& x) const {
    std::uint64_t k = 0;
    for (int a = 0; a < dim; ++a)
      k = (k << 21) | static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(x[a] / spacing_)) + (1 << 20));
    return k;
  }
  double spacing_, packing_;
  std::unordered_set<std::uint64_t> cells_;
};

}  // namespace

template <int dim>
SedimentPhase<dim> parse_sediment_phase(const mpm::Config& sediment) {
  using mpm::Range;
  SedimentPhase<dim> s;
  // A continuum by default when the map holds material keys, discrete grains otherwise.
  s.solver = sediment.choice("solver", sediment.has("youngs_modulus") ? "explicit" : "grains",
                             mpm::solid::solid_solver_names());
  s.implicit = mpm::solid::parse_implicit_settings(sediment, s.solver);
  if (s.solver != "grains") {
    s.materials.push_back(mpm::parse_material<dim>(sediment));
    s.density = s.materials.front().density;
  } else {
    s.density = sediment.number("density", Range::positive());
  }
  s.min_fluid_fraction = sediment.number("min_fluid_fraction", default_min_fluid_fraction, Range::open(0.0, 1.0));
  s.hold_until = sediment.number("hold_until", 0.0, Range::non_negative());
  if (const std::optional<mpm::Config> keys = sediment.optional_child("switching")) {
    if (s.materials.empty())
      sediment.fail("switching",
                    "switching needs a continuum sediment (youngs_modulus and the other keys of a "
                    "material)");
    SedimentSwitching t;
    t.dilute_below = keys->number("dilute_below", t.dilute_below, Range::open(0.0, 1.0));
    t.dense_above = keys->number("dense_above", t.dense_above, Range::open(t.dilute_below, 1.0));
    t.rouse_number = keys->number("rouse_number", t.rouse_number, Range::positive());
    s.switching = t;
  }
  return s;
}

namespace {
//! A sediment body that starts in equilibrium under its own buoyant weight, as a bed that has
//! settled (body key `geostatic: true`): the skeleton carries the overburden of its grains,
//! tau_vv = -(rho_s - rho_f) g h (h the depth below the body's top in the same lattice column,
//! the mixture stress being phi tau), in uniaxial strain (no lateral strain, Hencky: tau_vv =
//! (lambda + 2 mu) eps_vv). Without it a soft skeleton first consolidates under its weight and
//! expels pore fluid for seconds, which hides the pore pressure of the flow itself.
template <int dim>
void start_geostatic(CoupledScene<dim>& scene, std::size_t first, const std::vector<mpm::Vec<dim>>& x,
                     const mpm::Config& body) {
  if (!scene.sediment || scene.sediment->materials.empty() || scene.sediment->solver == "grains")
    body.fail("geostatic", "a geostatic start needs a continuum sediment (sediment.solver: explicit or implicit)");
  const mpm::Vec<dim>& g = scene.settings.gravity;
  int up = 0;
  try {
    up = vertical_axis(scene.settings);
  } catch (const mpm::InputError&) {
    body.fail("geostatic", "a geostatic start needs gravity along one coordinate axis, in its negative direction");
  }
  const double spacing =
      scene.settings.dx / mpm::geometry::lattice_points_per_axis<dim>(mpm::geometry::particles_per_cell<dim>(body));
  // The body's top per lattice column (positions rounded to the lattice across the vertical).
  const auto column = [&](const mpm::Vec<dim>& p) {
    std::array<long long, dim> key{};
    for (int a = 0; a < dim; ++a) key[a] = a == up ? 0 : std::llround(p[a] / spacing);
    return key;
  };
  std::map<std::array<long long, dim>, double> top;
  for (const mpm::Vec<dim>& p : x) {
    auto [it, inserted] = top.try_emplace(column(p), p[up]);
    if (!inserted) it->second = std::max(it->second, p[up]);
  }
  const double buoyant = scene.sediment->density - (scene.fluid ? scene.fluid->density : 0.0);
  const double modulus = scene.sediment->materials.front().lame.p_wave_modulus();  // lambda + 2 mu
  std::vector<mpm::Mat<dim>>& F = mpm::solid::elastic_F(scene.state.sediment.particles);
  for (std::size_t p = first, i = 0; p < F.size(); ++p, ++i) {
    const double depth = top.at(column(x[i])) + 0.5 * spacing - x[i][up];
    F[p](up, up) = std::exp(-buoyant * std::abs(g[up]) * depth / modulus);
  }
}

//! The overburden of a geostatic body needs something to rest on: below the base of each of its
//! columns of grid cells, the highest grid node at or below the base must be one an obstacle
//! prescribes (a closed wall's layer, a collider), or a grain of another sediment body must lie
//! within two cells below the base. The default wall layer is counted in cells, so a finer grid
//! lowers the floor of a domain drawn for a coarser one, and a bed would fall into the gap.
//! `owner[p]`: the body index of sediment particle p.
template <int dim>
void require_support(const CoupledScene<dim>& scene, const mpm::Config& body, std::size_t first, std::size_t end,
                     const std::vector<std::size_t>& owner) {
  const int up = vertical_axis(scene.settings);
  const double dx = scene.settings.dx;
  const mpm::Vec<dim>& lo = scene.settings.domain_lo;
  const mpm::Particles<dim>& P = scene.state.sediment.particles;
  using Cell = std::array<long long, dim>;
  const auto cell_of = [&](const mpm::Vec<dim>& x) {
    Cell c{};
    for (int a = 0; a < dim; ++a) c[a] = static_cast<long long>(std::floor((x[a] - lo[a]) / dx));
    return c;
  };
  // The cells that hold grains of another body.
  std::set<Cell> others;
  for (std::size_t p = 0; p < P.size(); ++p)
    if (owner[p] != owner[first]) others.insert(cell_of(P.x[p]));
  // The lowest grain of each column of grid cells (jittered seeding keeps its grains in it).
  std::map<Cell, mpm::Vec<dim>> bottom;
  for (std::size_t p = first; p < end; ++p) {
    Cell key = cell_of(P.x[p]);
    key[up] = 0;
    auto [it, inserted] = bottom.try_emplace(key, P.x[p]);
    if (!inserted && P.x[p][up] < it->second[up]) it->second = P.x[p];
  }
  const double spacing = dx / mpm::geometry::lattice_points_per_axis<dim>(mpm::geometry::particles_per_cell<dim>(body));
  for (const auto& [key, p] : bottom) {
    const double base = p[up] - 0.5 * spacing;
    mpm::Vec<dim> node = p;
    node[up] = lo[up] + std::floor((base - lo[up]) / dx + 1e-9) * dx;
    if (scene.colliders.prescribes(node, 0.0)) continue;
    mpm::Vec<dim> below = p;
    below[up] = base - 1e-9 * dx;
    Cell c = cell_of(below);
    if (others.count(c)) continue;
    --c[up];
    if (others.count(c)) continue;
    const char* axis = "xyz";
    std::string where =
        "nothing holds its base at " + std::string(1, axis[up]) + " = " + mpm::number_text(base) + " m (the column at";
    for (int a = 0; a < dim; ++a)
      if (a != up) where += " " + std::string(1, axis[a]) + " = " + mpm::number_text(p[a]) + " m";
    where += ")";
    const auto& walls = scene.colliders.walls();
    if (walls && walls->wall(up, mpm::geometry::Side::lower))
      where += ": the floor's wall layer is " + mpm::number_text(walls->thickness()) +
               " m deep (walls.thickness; (support - 1) grid.dx by default), so its top node is at " +
               mpm::number_text(lo[up] + std::floor(walls->thickness() / dx + 1e-9) * dx) + " m";
    body.fail("geostatic", "a geostatic body must rest on a closed wall, a collider or another sediment body, but " +
                               where + "; set walls.thickness in metres or move the body onto its support");
  }
}
}  // namespace

namespace {
//! The seeding lattice of `body` without the points inside the scene's own colliders (the first
//! `obstacles` of scene.colliders, phi < 0 at t = 0): an obstacle holds neither water nor grains,
//! so a pile through the bed or a pipe in the current starts empty. The flow boundaries'
//! colliders, appended after them (the inflow's section, which holds water), do not count.
template <int dim>
mpm::geometry::BodyParticles<dim> seed_outside_obstacles(const mpm::Config& body, const CoupledScene<dim>& scene,
                                                         std::size_t obstacles) {
  mpm::geometry::BodyParticles<dim> b = mpm::geometry::seed_body_shape<dim>(body, scene.settings);
  const auto& colliders = scene.colliders.colliders();
  std::erase_if(b.x, [&](const mpm::Vec<dim>& x) {
    for (std::size_t i = 0; i < obstacles; ++i)
      if (colliders[i].phi(x, 0.0) < 0.0) return true;
    return false;
  });
  if (b.x.empty()) body.fail("shape", "the body lies inside the colliders: no particle is left to seed");
  return b;
}

//! The bed-load closure's keys (coupling/bed_load.h); the grains' diameter is the drag law's.
template <int dim>
BedLoadLaw parse_bed_load(const mpm::Config& bed, const mpm::Config& scene, const CoupledScene<dim>& out) {
  using mpm::Range;
  if (!out.fluid || !out.sediment) scene.fail("bed_load", "the bed-load closure needs a fluid and a sediment");
  try {
    (void)vertical_axis(out.settings);
  } catch (const mpm::InputError& e) {
    scene.fail("gravity", e.what());
  }
  BedLoadLaw law;
  law.grain_diameter = scene.child("drag").number("grain_diameter", Range::positive());
  law.fluid_density = out.fluid->density;
  law.sediment_density = out.sediment->density;
  if (!(law.sediment_density > law.fluid_density))
    scene.fail("sediment", "the bed-load closure needs grains denser than the fluid");
  law.gravity = out.settings.gravity.norm();
  law.critical_shields = bed.number("critical_shields", law.critical_shields, Range::non_negative());
  law.coefficient = bed.number("coefficient", law.coefficient, Range::positive());
  law.exponent = bed.number("exponent", law.exponent, Range::positive());
  // A water column of one cell must lie inside the law's log layer, 11 h / k_s > e.
  const double largest_roughness = 11.0 * out.settings.dx / (std::exp(1.0) * law.grain_diameter);
  law.roughness = bed.number("roughness", law.roughness, Range::open(0.0, largest_roughness));
  law.morphological_factor = bed.number("morphological_factor", law.morphological_factor, Range::closed(1.0, 1e6));
  law.surface_fraction = bed.number("surface_fraction", law.surface_fraction, Range::open(0.0, 1.0));
  law.fluid_viscosity = out.fluid->viscosity;
  // The grains' step length: a length [m], or van Rijn's saltation length of each column.
  law.van_rijn_step = bed.text("step_length", "0") == "van_rijn";
  if (!law.van_rijn_step) law.step_length = bed.number("step_length", 0.0, Range::non_negative());
  // A bed packed no denser than the surface fraction would never show a surface.
  if (const mpm::Config sand = scene.child("sediment"); sand.has("packing_fraction")) {
    const double packing = sand.number("packing_fraction", Range::open(0.0, 1.0));
    if (!(law.surface_fraction < packing))
      bed.fail("surface_fraction", "must lie below sediment.packing_fraction (" + std::to_string(packing) + ")");
  }
  return law;
}
}  // namespace

template <int dim>
CoupledScene<dim> load_coupled_scene(const mpm::Config& scene) {
  using mpm::Range;
  using Vec = mpm::Vec<dim>;
  mpm::SceneSettings<dim> settings = mpm::parse_scene_settings<dim>(scene);
  // make_coupled_scene refuses them too, without the file position.
  for (int a = 0; a < dim; ++a)
    if (settings.periodic[a]) scene.fail("periodic", "coupled scenes have no periodic axes (the fluid alone has)");
  auto colliders = mpm::geometry::parse_colliders<dim>(scene, settings.domain_lo, settings.domain_hi,
                                                       mpm::wall_layer(settings.kernel, settings.dx));
  mpm::geometry::FlowBoundaries<dim> flow = mpm::geometry::parse_flow_boundaries<dim>(scene, settings);
  mpm::geometry::add_flow_boundaries(flow, colliders);
  std::optional<fluid::FluidMaterial> water;
  fluid::stages::PressureSettings pressure;
  fluid::FluidSolverSettings fluid_solver;
  if (const std::optional<mpm::Config> f = scene.optional_child("fluid")) {
    water = fluid::parse_fluid_material(*f);
    fluid_solver = fluid::parse_fluid_solver(*f);
    pressure = fluid::parse_pressure_settings(scene);
  }
  const std::optional<mpm::Config> sediment = scene.optional_child("sediment");
  std::optional<SedimentPhase<dim>> sand;
  if (sediment) sand = parse_sediment_phase<dim>(*sediment);
  // A collider's own contact for the sediment (collider key `sediment`: contact, friction), by
  // the list's index: parse_colliders adds the list first, add_flow_boundaries appends after it.
  for (const mpm::Config& entry : scene.list("colliders")) {
    const std::optional<mpm::Config> own = entry.optional_child("sediment");
    if (own && !sand) entry.fail("sediment", "the scene has no `sediment` map");
    if (sand) sand->contacts.push_back(own ? std::optional(mpm::geometry::parse_contact(*own)) : std::nullopt);
  }
  if (!water && !sand) scene.fail("fluid", "a coupled scene needs a `fluid` map, a `sediment` map or both");
  std::optional<drag::DragLaw> drag;
  if (water && sand) drag = drag::parse_drag_law(scene);
  if (flow.inflow && !water) scene.fail("inflow", "the inflow emits fluid, but the scene has no `fluid` map");
  CoupledScene<dim> out =
      make_coupled_scene<dim>(std::move(settings), std::move(colliders), water, pressure, sand, drag, fluid_solver);
  out.flow = std::move(flow);
  if (const std::optional<mpm::Config> bed = scene.optional_child("bed_load"))
    out.bed_load = parse_bed_load(*bed, scene, out);
  if (sand && sand->switching && !out.bed_load)
    if (const mpm::Config switching = scene.child("sediment").child("switching"); switching.has("rouse_number"))
      switching.fail("rouse_number",
                     "accepted only with a bed-load closure (scene key bed_load), whose friction velocity "
                     "the switch's suspension criterion needs");

  // The grain volume fraction of a body leaves the pore fluid at least n_min.
  std::optional<Range> packing;
  std::optional<double> default_packing;
  if (sand) {
    packing = Range{0.0, 1.0 - sand->min_fluid_fraction, true, false};
    if (sediment->has("packing_fraction")) default_packing = sediment->number("packing_fraction", *packing);
  }

  const std::size_t obstacles = scene.list("colliders").size();  // parse_colliders added them first
  const std::vector<mpm::Config> bodies = scene.list("bodies");
  std::vector<std::string> phase;
  for (const mpm::Config& body : bodies) {
    if (!body.has("phase")) body.fail("phase", "missing required key (fluid or sediment)");
    phase.push_back(body.choice("phase", "", {"fluid", "sediment"}));
    if (phase.back() == "fluid" && !water) body.fail("phase", "the scene has no `fluid` map");
    if (phase.back() == "sediment" && !sand) body.fail("phase", "the scene has no `sediment` map");
  }
  // Sediment first, so that every fluid body sees every pore.
  std::vector<Pores<dim>> pores;
  std::vector<std::array<std::size_t, 3>> geostatic;  // (body, its first particle, one past its last)
  std::vector<std::size_t> owner;                     // each sediment particle's body
  for (std::size_t n = 0; n < bodies.size(); ++n) {
    if (phase[n] != "sediment") continue;
    const mpm::Config& body = bodies[n];
    const double phi = default_packing ? body.number("packing_fraction", *default_packing, *packing)
                                       : body.number("packing_fraction", *packing);
    const mpm::geometry::BodyParticles<dim> b = seed_outside_obstacles(body, out, obstacles);
    const std::size_t first = out.state.sediment.particles.size();
    add_sediment_particles(out, b.x, phi * b.volume, body.vector<dim>("velocity", Vec::Zero()), body.path());
    if (body.flag("geostatic", false)) {
      start_geostatic(out, first, b.x, body);
      geostatic.push_back({n, first, out.state.sediment.particles.size()});
    }
    if (std::vector<double>* rest = mpm::solid::rest_packing(out.state.sediment.particles)) {
      const std::vector<mpm::Mat<dim>>& F = mpm::solid::elastic_F(out.state.sediment.particles);
      for (std::size_t p = first; p < rest->size(); ++p) (*rest)[p] = phi * F[p].determinant();
    }
    const int k = mpm::geometry::lattice_points_per_axis<dim>(mpm::geometry::particles_per_cell<dim>(body));
    pores.emplace_back(b.x, out.settings.dx / k, phi);
    owner.resize(out.state.sediment.particles.size(), n);
  }
  for (const auto& [n, first, end] : geostatic)  // every sediment body seeded: a bed may rest on another
    require_support(out, bodies[n], first, end, owner);
  for (std::size_t n = 0; n < bodies.size(); ++n) {
    if (phase[n] != "fluid") continue;
    const mpm::Config& body = bodies[n];
    const mpm::geometry::BodyParticles<dim> b = seed_outside_obstacles(body, out, obstacles);
    const Vec v = body.vector<dim>("velocity", Vec::Zero());
    std::vector<Vec> clear;
    std::vector<std::vector<Vec>> in_pores(pores.size());
    for (const Vec& x : b.x) {
      std::size_t j = 0;
      while (j < pores.size() && !pores[j].contain(x)) ++j;
      (j < pores.size() ? in_pores[j] : clear).push_back(x);
    }
    add_fluid_particles(out, clear, b.volume, 1.0, v, body.path());
    for (std::size_t j = 0; j < pores.size(); ++j)
      add_fluid_particles(out, in_pores[j], b.volume, 1.0 - pores[j].packing(), v, body.path());
  }

  if (out.fluid_solver) out.fluid_solver->start_at_rest(out.state.fluid.particles, out.settings);
  if (out.flow.inflow)
    out.fluid_sources.push_back(mpm::geometry::inflow_source(*out.flow.inflow, out.settings, water->density));
  for (const mpm::Config& emitter : scene.list("emitters")) {
    const std::string emits = emitter.choice("phase", "", {"fluid", "sediment"});
    if (emits == "fluid" && !water) emitter.fail("phase", "the scene has no `fluid` map");
    if (emits == "sediment" && !sand) emitter.fail("phase", "the scene has no `sediment` map");
    typename mpm::stages::ParticleSource<dim>::Settings source;
    source.lo = emitter.vector<dim>("lo");
    source.hi = emitter.vector<dim>("hi");
    mpm::geometry::require_inside_domain(emitter, source.lo, source.hi, out.settings);
    source.velocity = emitter.vector<dim>("velocity");
    source.dx = out.settings.dx;
    source.particles_per_cell = mpm::geometry::particles_per_cell<dim>(emitter);
    const double volume = mpm::geometry::particle_volume<dim>(out.settings.dx, source.particles_per_cell);
    source.start = emitter.number("start", 0.0, Range::non_negative());
    source.stop =
        emitter.number("stop", std::numeric_limits<double>::infinity(), Range{source.start, 1e308, true, true});
    if (emits == "fluid") {
      source.particle_volume = volume;
      source.particle_mass = water->density * volume;
      out.fluid_sources.push_back(source);
    } else {
      // A falling stream is dilute: its grains start discrete when the sediment switches.
      const double phi = default_packing ? emitter.number("packing_fraction", *default_packing, *packing)
                                         : emitter.number("packing_fraction", *packing);
      source.particle_volume = phi * volume;
      source.particle_mass = sand->density * phi * volume;
      source.material = sand->materials.empty() || sand->switching ? discrete_grain : std::uint16_t{0};
      out.sediment_sources.push_back(source);
    }
    try {
      mpm::stages::ParticleSource<dim> check(source);
    } catch (const mpm::InputError& e) {
      emitter.fail("lo", e.what());
    }
  }
  return out;
}

template SedimentPhase<2> parse_sediment_phase<2>(const mpm::Config&);
template SedimentPhase<3> parse_sediment_phase<3>(const mpm::Config&);
template CoupledScene<2> load_coupled_scene<2>(const mpm::Config&);
template CoupledScene<3> load_coupled_scene<3>(const mpm::Config&);

}  // namespace coupling
