// The fluid step (libfluid stages and scene): after the pressure projection the discrete
// divergence D u of the node velocities vanishes in every fluid cell (single phase, and the
// mixture flux n_w v_w + n_s v_s with a second phase), nodes that walls prescribe are left
// untouched, a closed cavity with a moving lid and an empty cell stays solvable (only the
// null-space part of D u remains), a missed tolerance stops or warns as configured, a tank at
// rest stays at rest with a hydrostatic cell pressure while the phase mass is conserved
// exactly, the implicit viscosity solves its backward-Euler system, and bad scene input fails
// naming the key.
#include <fluid/scene/fluid_scene.h>
#include <fluid/stages/equation_of_state.h>
#include <fluid/stages/implicit_viscosity.h>
#include <fluid/stages/prescribed_nodes.h>
#include <fluid/stages/pressure_projection.h>

#include <mpm/core/advance.h>
#include <mpm/core/error.h>
#include <mpm/core/stages/grid_boundary.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

using namespace mpm;

namespace {

//! A tank (walls 2 dx thick with `contact`, open top) holding water 0.15 m deep on its floor.
template <int dim>
std::string tank_yaml(const std::string& extra = "", const std::string& contact = "sticky") {
  const std::string v = dim == 2 ? "[0, -9.81]" : "[0, -9.81, 0]";
  const std::string lo = dim == 2 ? "[0, 0]" : "[0, 0, 0]";
  const std::string hi = dim == 2 ? "[0.5, 0.5]" : "[0.5, 0.5, 0.5]";
  const std::string water = dim == 2 ? "[0.45, 0.2]" : "[0.4, 0.25, 0.4]";
  const std::string origin = dim == 2 ? "[0.05, 0.05]" : "[0.1, 0.1, 0.1]";
  return "dim: " + std::to_string(dim) + "\ndomain: {lo: " + lo + ", hi: " + hi + "}\n" +
         "grid: {dx: " + (dim == 2 ? "0.025" : "0.05") + "}\n" + "time: {end: 1.0, frame_dt: 0.05}\ngravity: " + v +
         "\n" + "fluid: {density: 1000, viscosity: 0.0}\n" +
         "pressure: {solver: cg, tolerance: 1.0e-12, max_iterations: 5000}\n" + "walls: {contact: " + contact +
         ", y_max: open}\n" + "bodies:\n  - {shape: box, lo: " + origin + ", hi: " + water + "}\n" + extra;
}

//! Node velocities of the operator box of `stage` (zero where the grid has no node).
template <int dim>
std::vector<Vec<dim>> box_velocities(const fluid::stages::PressureProjection<dim>& stage, const SparseGrid<dim>& g) {
  const auto& op = stage.cell_operator();
  std::vector<Vec<dim>> u(static_cast<std::size_t>(op.node_count()), Vec<dim>::Zero());
  IVec<dim> n = IVec<dim>::Zero();
  for (std::size_t i = 0; i < u.size(); ++i) {
    const Index k = g.node_index(stage.box_origin() + n);
    if (k >= 0) u[i] = g.velocity[k];
    for (int a = 0; a < dim; ++a) {
      if (++n[a] <= op.cells[a]) break;
      n[a] = 0;
    }
  }
  return u;
}

template <int dim>
double max_fluid_divergence(const fluid::CellOperator<dim>& op, const std::vector<Vec<dim>>& u) {
  std::vector<double> div;
  op.divergence(u, div);
  double m = 0.0;
  for (std::size_t c = 0; c < div.size(); ++c)
    if (op.type[c] == fluid::CellType::fluid) m = std::max(m, std::abs(div[c]));
  return m;
}

//! Scene with random particle velocities, advanced through P2G, gravity and the walls.
template <int dim>
fluid::FluidScene<dim> stirred_tank(unsigned seed, const std::string& contact = "sticky") {
  const Config cfg = Config::parse(tank_yaml<dim>("", contact), "tank.yaml");
  fluid::FluidScene<dim> scene = fluid::load_fluid_scene<dim>(cfg);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Vec<dim>& v : scene.state.particles.v)
    for (int a = 0; a < dim; ++a) v[a] = u(rng);
  MpmState<dim>& s = scene.state;
  s.dt = 2e-3;
  stages::SortParticles<dim>().run(s);
  stages::ParticlesToGrid<dim>().run(s);
  stages::GridVelocityUpdate<dim>(false).run(s);
  stages::GridBoundary<dim>(scene.colliders).run(s);
  return scene;
}

template <int dim>
void check_projection_divergence_free(const std::string& contact) {
  CAPTURE(contact);
  fluid::FluidScene<dim> scene = stirred_tank<dim>(7, contact);
  MpmState<dim>& s = scene.state;
  const std::vector<Vec<dim>> before = s.grid.velocity;
  fluid::stages::PressureProjection<dim> projection(1000.0, scene.colliders, scene.pressure);
  projection.run(s);
  REQUIRE(projection.last_result().converged);

  // Divergence before (recomputed on the same box from the saved velocities) and after.
  const auto& op = projection.cell_operator();
  std::vector<Vec<dim>> saved = s.grid.velocity;
  s.grid.velocity = before;
  const double div_before = max_fluid_divergence(op, box_velocities(projection, s.grid));
  s.grid.velocity = saved;
  const double div_after = max_fluid_divergence(op, box_velocities(projection, s.grid));
  CHECK(div_before > 1.0);  // [1/s]: the random field is far from solenoidal
  CHECK(div_after < 1e-9 * div_before);

  // Held wall nodes (sticky, or in a corner) and nodes without mass keep their velocity
  // exactly; slipping wall nodes the components the walls hold, while the pressure moves them
  // along.
  const auto fixed = fluid::stages::prescribed_nodes(s.grid, scene.colliders, s.time + s.dt);
  std::size_t held = 0, slipping = 0, moved = 0;
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k) {
    if (s.grid.mass[k] <= 0.0) CHECK(s.grid.velocity[k] == before[k]);
    if (!fixed[k]) continue;
    const auto free = fluid::stages::slip_directions(scene.colliders, s.grid.node_position(k), s.time + s.dt);
    if (!free) {
      ++held;
      CHECK(s.grid.velocity[k] == before[k]);
      continue;
    }
    ++slipping;
    const Vec<dim> change = s.grid.velocity[k] - before[k];
    CHECK(((Mat<dim>::Identity() - *free) * change).norm() <= 1e-15);
    moved += change.norm() > 1e-3;
  }
  CHECK(held > 0);
  if (contact == "sticky") CHECK(slipping == 0);
  if (contact == "slip") CHECK(4 * moved > slipping);  // the deeper nodes of the wall layer border no water
}

template <int dim>
void check_mixture_constraint() {
  fluid::FluidScene<dim> scene = stirred_tank<dim>(11);
  MpmState<dim>& s = scene.state;
  const std::size_t n = s.grid.node_storage();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  fluid::stages::MixtureNodes<dim> mixture;
  const double rho_s = 2650.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double ns = 0.6 * u(rng);
    Vec<dim> vs;
    for (int a = 0; a < dim; ++a) vs[a] = u(rng) - 0.5;
    mixture.fluid_fraction.push_back(1.0 - ns);
    mixture.solid_flux.push_back(ns * vs);
    mixture.solid_mobility.push_back(ns / rho_s);
  }
  fluid::stages::PressureProjection<dim> projection(1000.0, scene.colliders, scene.pressure);
  projection.set_mixture(&mixture);
  projection.run(s);
  REQUIRE(projection.last_result().converged);

  // Mixture flux after the step: n_w v_w + n_s v_s^* + dt (n_s / rho_s) D^T p on free nodes,
  // the water's (the walls') velocity where the walls hold the mixture (the tank is sticky).
  const auto& op = projection.cell_operator();
  const auto held = fluid::stages::prescribed_nodes(s.grid, scene.colliders, s.time + s.dt);
  const std::vector<Vec<dim>> vw = box_velocities(projection, s.grid);
  std::vector<Vec<dim>> impulse(vw.size(), Vec<dim>::Zero());  // beta D^T p
  op.subtract_gradient(projection.pressure(), impulse);
  std::vector<Vec<dim>> flux(vw.size(), Vec<dim>::Zero());
  IVec<dim> c = IVec<dim>::Zero();
  for (std::size_t i = 0; i < vw.size(); ++i) {
    const Index k = s.grid.node_index(projection.box_origin() + c);
    if (k >= 0) {
      flux[i] = held[k] ? vw[i] : mixture.fluid_fraction[k] * vw[i] + mixture.solid_flux[k];
      if (op.beta[i] > 0.0) flux[i] += (s.dt * mixture.solid_mobility[k] / op.beta[i]) * impulse[i];
    }
    for (int a = 0; a < dim; ++a) {
      if (++c[a] <= op.cells[a]) break;
      c[a] = 0;
    }
  }
  const double div_fluid_only = max_fluid_divergence(op, vw);
  CHECK(div_fluid_only > 1e-3);  // the water alone is not solenoidal: the mixture is
  CHECK(max_fluid_divergence(op, flux) < 1e-9 * div_fluid_only);
}

}  // namespace

TEST_CASE("pressure projection: D u = 0 in every fluid cell, walls held or slipping (2D, 3D)") {
  for (const std::string contact : {"sticky", "slip"}) {
    check_projection_divergence_free<2>(contact);
    check_projection_divergence_free<3>(contact);
  }
}

TEST_CASE("pressure projection: mixture constraint div(n_w v_w + n_s v_s) = 0") { check_mixture_constraint<2>(); }

TEST_CASE("pressure projection: a closed cavity with a moving lid and one empty cell is solvable") {
  // Every wall closed and the lid sliding: A has the Q1-P0 null vectors, and the lid makes
  // -D u inconsistent with the checkerboard; the stage must remove that part of b.
  const Config cfg = Config::parse(tank_yaml<2>(), "cavity.yaml");
  SceneSettings<2> settings = parse_scene_settings<2>(cfg);
  auto colliders = geometry::parse_colliders<2>(cfg, settings.domain_lo, settings.domain_hi, 2 * settings.dx);
  colliders.add(geometry::Collider<2>(geometry::HalfSpace<2>(Vec<2>(0.0, 0.45), Vec<2>(0.0, -1.0)),
                                      geometry::Contact{geometry::ContactType::sticky, 0.0}, Vec<2>(1.0, 0.0)));
  fluid::FluidScene<2> scene = fluid::make_fluid_scene(settings, fluid::parse_fluid_material(cfg.child("fluid")),
                                                       fluid::parse_pressure_settings(cfg), colliders);
  std::vector<Vec<2>> x = geometry::seed_box<2>(Vec<2>(0.05, 0.05), Vec<2>(0.45, 0.45), settings.dx, 4, 0.0, 1);
  std::erase_if(x, [](const Vec<2>& p) { return p[0] > 0.2 && p[0] < 0.225 && p[1] > 0.2 && p[1] < 0.225; });
  fluid::add_fluid_particles<2>(scene, x, 1e-4, Vec<2>::Zero(), "cavity");
  MpmState<2>& s = scene.state;
  s.dt = 1e-2;
  stages::SortParticles<2>().run(s);
  stages::ParticlesToGrid<2>().run(s);
  stages::GridVelocityUpdate<2>(false).run(s);
  stages::GridBoundary<2>(scene.colliders).run(s);
  fluid::stages::PressureProjection<2> projection(1000.0, scene.colliders, scene.pressure);
  projection.run(s);
  CHECK(projection.last_result().converged);
  CHECK(projection.last_result().relative_residual < 1e-12);
  // What is left of D u is the removed null-space part of b, a constant on each checkerboard
  // colour; anything else would be an unsolved divergence.
  const auto& op = projection.cell_operator();
  std::vector<double> div;
  op.divergence(box_velocities(projection, s.grid), div);
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300}, largest = 0.0;
  for (int j = 0; j < op.cells[1]; ++j)
    for (int i = 0; i < op.cells[0]; ++i) {
      const std::int64_t c = op.cell_index(IVec<2>(i, j));
      if (op.type[c] != fluid::CellType::fluid) continue;
      const int colour = (i + j) % 2;
      lo[colour] = std::min(lo[colour], div[c]);
      hi[colour] = std::max(hi[colour], div[c]);
      largest = std::max(largest, std::abs(div[c]));
    }
  CHECK(hi[0] - lo[0] < 1e-9);  // [1/s]; the lid drives |div| of order U / dx = 40 before
  CHECK(hi[1] - lo[1] < 1e-9);
  CHECK(largest < 1.0);
}

TEST_CASE("pressure projection: a solve that misses its tolerance stops or warns as the scene says") {
  for (const auto on_failure : {fluid::stages::OnFailure::stop, fluid::stages::OnFailure::warn}) {
    fluid::FluidScene<2> scene = stirred_tank<2>(13);
    fluid::stages::PressureSettings settings = scene.pressure;
    settings.control.max_iterations = 2;
    settings.on_failure = on_failure;
    fluid::stages::PressureProjection<2> projection(1000.0, scene.colliders, settings);
    std::string message;
    try {
      projection.run(scene.state);
    } catch (const NumericalError& e) {
      message = e.what();
    }
    CHECK_FALSE(projection.last_result().converged);
    if (on_failure == fluid::stages::OnFailure::stop) {
      CHECK(message.find("stage 'pressure'") != std::string::npos);
      CHECK(message.find("2 iterations") != std::string::npos);
      CHECK(message.find("relative residual") != std::string::npos);
    } else {
      CHECK(message.empty());
    }
  }
}

TEST_CASE("hydrostatic tank: at rest after 1 s, hydrostatic pressure, mass conserved exactly") {
  // surface_extension off: the nodes one row above the surface hold mass but are no corner of a
  // fluid cell, so they fall freely and pull the top particles down (the spurious currents).
  for (const bool extension : {true, false}) {
    CAPTURE(extension);
    std::string yaml = tank_yaml<2>();
    if (!extension)
      yaml.replace(yaml.find("max_iterations: 5000}"), 21, "max_iterations: 5000, surface_extension: false}");
    const Config cfg = Config::parse(yaml, "tank.yaml");
    fluid::FluidScene<2> scene = fluid::load_fluid_scene<2>(cfg);
    auto pipeline = fluid::make_fluid_pipeline(scene);
    MpmState<2>& s = scene.state;
    double particle_mass = 0.0;
    for (double m : s.particles.mass) particle_mass += m;
    const std::size_t count = s.particles.size();
    mpm::advance(s, pipeline, 1.0);
    // Phase mass: particles carry it unchanged and P2G hands all of it to the grid.
    double after = 0.0, grid = 0.0;
    for (double m : s.particles.mass) after += m;
    for (double m : s.grid.mass) grid += m;
    CHECK(s.particles.size() == count);
    CHECK(after == particle_mass);
    CHECK(std::abs(grid - particle_mass) <= 1e-12 * particle_mass);

    const double h = 0.15, g = 9.81, rho = 1000.0;
    double speed = 0.0;
    for (const Vec<2>& v : s.particles.v) speed = std::max(speed, v.norm());
    // 6 cells deep; free fall would reach 9.8 m/s. Measured: 4.8e-14 m/s with the extension (the
    // pressure tolerance is 1e-12), 1.5e-3 m/s without.
    if (extension)
      CHECK(speed < 1e-10 * std::sqrt(g * h));
    else
      CHECK(speed > 1e-4 * std::sqrt(g * h));
    // Cell pressure at mid depth against rho g (h - y): first order, half a cell of surface offset.
    const auto* projection = pipeline.find<fluid::stages::PressureProjection<2>>();
    REQUIRE(projection);
    const double floor = 0.05, y = floor + 0.5 * h;
    const double p = projection->pressure_at(s.grid, Vec<2>(0.25, y));
    CHECK(std::abs(p - rho * g * (floor + h - y)) < 0.1 * rho * g * h);
  }
}

TEST_CASE("surface extension: a blob in free fall keeps falling freely, in 2D and 3D") {
  // No walls, no pressure (v* is uniform, D v* = 0): every node, loose or not, has v*, and the
  // extension hands the loose ones the mean of identical values.
  auto fall = [](auto dim_tag) {
    constexpr int dim = decltype(dim_tag)::value;
    const std::string g = dim == 2 ? "[0, -9.81]" : "[0, -9.81, 0]";
    const std::string lo = dim == 2 ? "[0, 0]" : "[0, 0, 0]", hi = dim == 2 ? "[1, 1]" : "[1, 1, 1]";
    const std::string blob_lo = dim == 2 ? "[0.3, 0.5]" : "[0.3, 0.5, 0.3]";
    const std::string blob_hi = dim == 2 ? "[0.53, 0.71]" : "[0.53, 0.71, 0.53]";
    const Config cfg = Config::parse("dim: " + std::to_string(dim) + "\ndomain: {lo: " + lo + ", hi: " + hi +
                                         "}\ngrid: {dx: 0.05}\ntime: {end: 1}\ngravity: " + g +
                                         "\nfluid: {density: 1000, viscosity: 0}\n" +
                                         "pressure: {solver: cg, tolerance: 1.0e-12}\nwalls: {contact: sticky}\n" +
                                         "bodies:\n  - {shape: box, lo: " + blob_lo + ", hi: " + blob_hi + "}\n",
                                     "fall.yaml");
    fluid::FluidScene<dim> scene = fluid::load_fluid_scene<dim>(cfg);
    auto pipeline = fluid::make_fluid_pipeline(scene);
    mpm::advance(scene.state, pipeline, 0.02);
    double diagnostics_extended = 0.0;
    for (const Diagnostic& d : pipeline.diagnostics())
      if (d.name == "surface_nodes_extended") diagnostics_extended = d.value;
    CHECK(diagnostics_extended > 0.0);  // the blob does have loose nodes
    const Vec<dim> v = scene.state.time * scene.settings.gravity;
    for (const Vec<dim>& vp : scene.state.particles.v) CHECK((vp - v).norm() <= 1e-12 * v.norm());
  };
  fall(std::integral_constant<int, 2>{});
  fall(std::integral_constant<int, 3>{});
}

TEST_CASE("weakly compressible tank: hydrostatic pressure from the equation of state, mass exact") {
  // The same tank with the pressure from each particle's volume (fluid.solver:
  // weakly_compressible): the liquid compresses until p(J) balances its weight. A little
  // viscosity damps the sound waves the release starts.
  const Config cfg =
      Config::parse(tank_yaml<2>(), "tank.yaml",
                    {"fluid.solver=weakly_compressible", "fluid.speed_of_sound=15", "fluid.viscosity=2"});
  fluid::FluidScene<2> scene = fluid::load_fluid_scene<2>(cfg);
  REQUIRE(scene.solver->name() == "weakly_compressible");
  auto pipeline = fluid::make_fluid_pipeline(scene);
  const auto names = pipeline.stage_names();
  CHECK(std::find(names.begin(), names.end(), "pressure") == names.end());  // no linear solve
  MpmState<2>& s = scene.state;
  const double mass = s.particles.total_mass();
  mpm::advance(s, pipeline, 1.0);
  CHECK(s.particles.total_mass() == mass);

  // Mean particle pressure in bands of the column against rho g (depth), away from the walls.
  const double h = 0.15, g = 9.81, rho = 1000.0, floor = 0.05;
  const fluid::TaitEquationOfState eos{rho, 15.0, 7.0};
  const std::vector<double>& J = s.particles.channel<double>(fluid::kVolumeRatio);
  for (const double depth : {0.25 * h, 0.5 * h, 0.75 * h}) {
    double sum = 0.0;
    int n = 0;
    for (std::size_t p = 0; p < J.size(); ++p) {
      const Vec<2>& x = s.particles.x[p];
      if (std::abs(x[1] - (floor + h - depth)) < 0.0125 && x[0] > 0.15 && x[0] < 0.35) {
        sum += eos.pressure(J[p]);
        ++n;
      }
    }
    REQUIRE(n > 0);
    CAPTURE(depth);
    CHECK(sum / n == doctest::Approx(rho * g * depth).epsilon(0.08));
  }
  // Compressed by about g h / c^2 = 0.65 %, far from the 1 / J = 2 that would mean a collapse.
  double deviation = 1.0;
  for (const mpm::Diagnostic& d : pipeline.diagnostics())
    if (d.name == "density_deviation") deviation = d.value;
  CHECK(deviation > 0.0);
  CHECK(deviation < 0.02);
}

TEST_CASE("weakly compressible liquid starts at hydrostatic equilibrium, not at J = 1") {
  // The tank's surface is at y = 0.2 (the box 0.05 .. 0.2 seeded on a lattice): after loading,
  // every particle's p(J) is rho g (0.2 - y). Then the first 0.05 s: the liquid seeded at J = 1
  // (fluid.initial_pressure: zero) falls into its own weight; the one at equilibrium stays
  // almost still, next to the walls too.
  const double rho = 1000.0, g = 9.81, surface = 0.2, depth = 0.15;
  const fluid::TaitEquationOfState eos{rho, 15.0, 7.0};
  const auto tank = [](const std::string& start) {
    return fluid::load_fluid_scene<2>(Config::parse(
        tank_yaml<2>(), "tank.yaml",
        {"fluid.solver=weakly_compressible", "fluid.speed_of_sound=15", "fluid.initial_pressure=" + start}));
  };
  fluid::FluidScene<2> at_rest = tank("hydrostatic"), released = tank("zero");
  const std::vector<double>& J = at_rest.state.particles.channel<double>(fluid::kVolumeRatio);
  double worst = 0.0;
  for (std::size_t p = 0; p < J.size(); ++p)
    worst = std::max(worst, std::abs(eos.pressure(J[p]) - rho * g * (surface - at_rest.state.particles.x[p][1])));
  CHECK(worst <= 1e-9 * rho * g * depth);
  for (const double j : released.state.particles.channel<double>(fluid::kVolumeRatio)) REQUIRE(j == 1.0);

  const auto fastest_after = [](fluid::FluidScene<2>& scene, double t) {
    auto pipeline = fluid::make_fluid_pipeline(scene);
    mpm::advance(scene.state, pipeline, t);
    double speed = 0.0;
    for (const Vec<2>& v : scene.state.particles.v) speed = std::max(speed, v.norm());
    return speed;
  };
  const double still = fastest_after(at_rest, 0.05), falling = fastest_after(released, 0.05);
  MESSAGE("fastest particle after 0.05 s: " << still << " m/s at equilibrium, " << falling << " m/s from J = 1");
  // Without the walls' images (WallPressureForces) the columns next to the walls move at
  // 0.1 times the falling speed and their pressure is 26 % of rho g h off; with them 0.005 and 2.3 %.
  CHECK(still < 0.02 * falling);
  worst = 0.0;
  for (std::size_t p = 0; p < J.size(); ++p)
    worst = std::max(worst, std::abs(eos.pressure(J[p]) - rho * g * (surface - at_rest.state.particles.x[p][1])));
  MESSAGE("largest pressure error after 0.05 s, every particle: " << worst / (rho * g * depth) << " rho g h");
  CHECK(worst < 0.05 * rho * g * depth);
}

TEST_CASE("implicit viscosity: (I - dt nu L) v = v* on the nodes, walls as Dirichlet data") {
  fluid::FluidScene<2> scene = stirred_tank<2>(5);
  MpmState<2>& s = scene.state;
  const std::vector<Vec<2>> v_star = s.grid.velocity;
  const double nu = 1e-2, c = s.dt * nu / (s.grid.dx() * s.grid.dx());
  fluid::stages::ImplicitViscosity<2> viscosity(nu, scene.colliders, {1e-12, 0.0, 1000});
  viscosity.run(s);
  REQUIRE(viscosity.last_result().converged);
  const auto fixed = fluid::stages::prescribed_nodes(s.grid, scene.colliders, s.time + s.dt);
  double residual = 0.0, change = 0.0;
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k) {
    if (s.grid.mass[k] <= 0.0 || fixed[k]) continue;
    const IVec<2> node = s.grid.node_coord(k);
    Vec<2> Lv = Vec<2>::Zero();
    for (int j = 0; j < 4; ++j) {
      IVec<2> other = node;
      other[j / 2] += j % 2 ? 1 : -1;
      const Index m = s.grid.node_index(other);
      if (m < 0 || s.grid.mass[m] <= 0.0) continue;
      Vec<2> vm = s.grid.velocity[m];
      if (fixed[m]) scene.colliders.project(s.grid.node_position(m), s.time + s.dt, vm);
      Lv += vm - s.grid.velocity[k];
    }
    residual = std::max(residual, (s.grid.velocity[k] - c * Lv - v_star[k]).norm());
    change = std::max(change, (s.grid.velocity[k] - v_star[k]).norm());
  }
  CHECK(change > 1e-2);
  CHECK(residual < 1e-9);
}

TEST_CASE("fluid scene: bad input names file, key and range") {
  auto message = [](const std::string& extra_or_override) {
    try {
      const Config cfg = Config::parse(tank_yaml<2>(), "tank.yaml", {extra_or_override});
      fluid::load_fluid_scene<2>(cfg);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string viscosity = message("fluid.viscosity=-1");
  CHECK(viscosity.find("fluid.viscosity") != std::string::npos);
  CHECK(viscosity.find(">= 0") != std::string::npos);
  const std::string density = message("fluid.density=0");
  CHECK(density.find("fluid.density") != std::string::npos);
  CHECK(density.find("> 0") != std::string::npos);
  const std::string solver = message("pressure.solver=magic");
  CHECK(solver.find("pressure.solver") != std::string::npos);
  CHECK(solver.find("cg") != std::string::npos);
  CHECK(message("time.cfl=1.5").find("time.cfl") != std::string::npos);
}
