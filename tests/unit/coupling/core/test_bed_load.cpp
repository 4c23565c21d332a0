// The bed-load closure (coupling/bed_load.h): the transport formula and the wall law against the
// reference's numbers, the layer's exchange limited to the wall stress with momentum conserved,
// the grains' drift carrying the formula's flux, a bed that the drag of a current no longer
// strips, and the keys' errors.
#include <coupling/bed_load.h>
#include <coupling/momentum_exchange.h>
#include <coupling/scene_loader.h>
#include <coupling/stages/bed_load.h>
#include <doctest/doctest.h>
#include <mpm/core/advance.h>
#include <mpm/core/error.h>
#include <mpm/solid/solid_channels.h>

#include <algorithm>
#include <cmath>
#include <string>

using namespace coupling;
using mpm::Vec;

namespace {

//! A flume as the flagship's at half its size: a bed 0.3 m long and 0.05 m deep between sills,
//! under 0.07 m of water entering at 0.4 m/s and leaving over a weir 2 cm above the bed;
//! `bed_load` is the closure's map (empty: none), `sediment` more keys of the sediment map.
mpm::Config flume(const std::string& bed_load, const std::string& sediment = "") {
  return mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, -0.01], hi: [0.4, 0.16]}
grid: {dx: 0.005}
time: {end: 1}
gravity: [0, -9.81]
walls: {contact: sticky}
fluid: {density: 1000, viscosity: 1.0e-3}
pressure: {solver: mgpcg, tolerance: 1.0e-9}
drag: {law: di_felice, grain_diameter: 5.0e-4}
sediment: {density: 2650, youngs_modulus: 5.0e4, poisson_ratio: 0.3, elasticity: hencky_stvk,
           plasticity: {model: drucker_prager, friction_angle: 32})" +
                            sediment + R"(}
inflow: {face: x_min, velocity: [0.4, 0], lo: [0, 0.05], hi: [0.02, 0.12], particles_per_cell: 4}
outflow: {face: x_max}
colliders:
  - {type: box, lo: [-0.1, -0.1], hi: [0.05, 0.05], contact: sticky}
  - {type: box, lo: [0.35, -0.1], hi: [0.5, 0.07], contact: sticky}
bodies:
  - {phase: sediment, shape: box, lo: [0.05, 0], hi: [0.35, 0.05], packing_fraction: 0.6, geostatic: true}
  - {phase: fluid, shape: box, lo: [0.05, 0], hi: [0.35, 0.05]}
  - {phase: fluid, shape: box, lo: [0.01, 0.05], hi: [0.39, 0.12], velocity: [0.4, 0]}
)" + bed_load);
}

//! The mean distance the grains of the bed's top 5 mm away from its ends moved along the
//! current [m].
double surface_shift(const CoupledState<2>& s, const std::vector<Vec<2>>& x0) {
  double shift = 0.0;
  int n = 0;
  for (std::size_t p = 0; p < x0.size(); ++p)
    if (x0[p][1] > 0.045 && x0[p][0] > 0.1 && x0[p][0] < 0.3) {
      shift += s.sediment.particles.x[p][0] - x0[p][0];
      ++n;
    }
  return shift / n;
}

//! The same flume in 3D, 3 cm wide between closed side walls, at dx = 5 mm.
mpm::Config flume_3d(const std::string& bed_load) {
  return mpm::Config::parse(R"(
dim: 3
domain: {lo: [0, -0.01, -0.01], hi: [0.4, 0.14, 0.04]}
grid: {dx: 0.005}
time: {end: 1}
gravity: [0, -9.81, 0]
walls: {contact: sticky}
fluid: {density: 1000, viscosity: 1.0e-3}
pressure: {solver: mgpcg, tolerance: 1.0e-9}
drag: {law: di_felice, grain_diameter: 5.0e-4}
sediment: {density: 2650, youngs_modulus: 5.0e4, poisson_ratio: 0.3, elasticity: hencky_stvk,
           plasticity: {model: drucker_prager, friction_angle: 32}}
inflow: {face: x_min, velocity: [0.4, 0, 0], lo: [0, 0.05, 0], hi: [0.02, 0.12, 0.03], particles_per_cell: 8}
outflow: {face: x_max}
colliders:
  - {type: box, lo: [-0.1, -0.1, -0.1], hi: [0.05, 0.05, 0.1], contact: sticky}
  - {type: box, lo: [0.35, -0.1, -0.1], hi: [0.5, 0.07, 0.1], contact: sticky}
bodies:
  - {phase: sediment, shape: box, lo: [0.05, 0, 0], hi: [0.35, 0.05, 0.03], packing_fraction: 0.6, geostatic: true}
  - {phase: fluid, shape: box, lo: [0.05, 0, 0], hi: [0.35, 0.05, 0.03]}
  - {phase: fluid, shape: box, lo: [0.01, 0.05, 0], hi: [0.39, 0.12, 0.03], velocity: [0.4, 0, 0]}
)" + bed_load);
}

template <int dim>
Vec<dim> momentum_of(const mpm::SparseGrid<dim>& g) {
  Vec<dim> m = Vec<dim>::Zero();
  for (std::size_t k = 0; k < g.node_storage(); ++k) m += g.mass[k] * g.velocity[k];
  return m;
}

//! One step of the flume, then: one layer per bed column (the surface node, n_s >= the surface
//! fraction and free of the walls and sills, and the node above it, below it), the stress along
//! the current; the exchange followed by the limit keeps the grids' momentum, and per column the
//! grains' tangential impulse is at most the wall stress's, equal to it where limited. `columns_expected`: the
//! bed's node columns off the walls' layers and the sills.
template <int dim>
void check_layer_and_limit(const mpm::Config& config, std::size_t columns_expected) {
  CoupledScene<dim> scene = load_coupled_scene<dim>(config);
  auto pipeline = make_coupled_pipeline(scene);
  CoupledState<dim>& s = scene.state;
  mpm::advance(s, pipeline, 0.01);  // grids, fractions and velocities of a step
  const BedLoadLaw law = *scene.bed_load;

  BedLayer<dim> layer;
  find_bed_layer(law, 1, s.fluid.grid, s.sediment.grid, s.fractions, scene.colliders, s.time, layer);
  REQUIRE(!layer.nodes.empty());
  std::size_t columns = 0;
  for (std::size_t i = 0; i < layer.nodes.size(); ++i) {
    const BedLayerNode<dim>& n = layer.nodes[i];
    if (i == 0 || layer.nodes[i - 1].column != n.column) {
      ++columns;
      CHECK(s.fractions.sediment[n.sediment] >= law.surface_fraction);
      CHECK_FALSE(scene.colliders.prescribes(s.sediment.grid.node_position(n.sediment), s.time));
    } else {
      CHECK(s.fractions.sediment[n.sediment] < law.surface_fraction);
      CHECK(s.sediment.grid.node_coord(n.sediment) ==
            s.sediment.grid.node_coord(layer.nodes[i - 1].sediment) + mpm::IVec<dim>::Unit(1));
    }
  }
  CHECK(columns == columns_expected);
  const Vec<dim> mid = layer.stress[static_cast<std::size_t>(layer.nodes[layer.nodes.size() / 2].column)];
  CHECK(mid[0] > 0.0);
  CHECK(mid[1] == 0.0);

  mpm::SparseGrid<dim> fluid = s.fluid.grid, sediment = s.sediment.grid;
  const Vec<dim> before = momentum_of(fluid) + momentum_of(sediment);
  std::vector<double> beta;
  const double dt = 1e-3;
  MomentumExchange<dim>(*scene.drag).apply(fluid, sediment, s.fractions.fluid, dt, beta);
  const std::size_t limited = limit_bed_shear(layer, fluid, sediment, dt);
  CHECK(limited >= columns_expected / 2);  // the dense bed's drag far exceeds a wall stress of ~0.2 Pa
  const Vec<dim> after = momentum_of(fluid) + momentum_of(sediment);
  CHECK((after - before).norm() <= 1e-13 * (momentum_of(fluid).norm() + 1.0));
  std::vector<Vec<dim>> impulse(layer.stress.size(), Vec<dim>::Zero());
  for (const BedLayerNode<dim>& n : layer.nodes) {
    Vec<dim> dv = sediment.velocity[n.sediment] - n.v_s;
    dv[1] = 0.0;
    impulse[std::size_t(n.column)] += sediment.mass[n.sediment] * dv;
  }
  std::size_t at_stress = 0;
  for (std::size_t c = 0; c < impulse.size(); ++c) {
    const double allowed = layer.stress[c].norm() * std::pow(s.sediment.grid.dx(), dim - 1) * dt;
    CHECK(impulse[c].norm() <= allowed * (1 + 1e-12) + 1e-300);
    if (allowed > 0.0 && impulse[c].norm() >= allowed * (1 - 1e-12)) ++at_stress;
  }
  CHECK(at_stress == limited);
}

//! One step of the flume with transport: the grains' drift carries the layer's flux (the gather
//! is the P2G's adjoint), and per column the layer carries the formula's flux, or less where
//! the drift is capped at the water's speed (none here: the drift is well below it).
template <int dim>
void check_drift_flux(const mpm::Config& config) {
  CoupledScene<dim> scene = load_coupled_scene<dim>(config);
  auto pipeline = make_coupled_pipeline(scene);
  CoupledState<dim>& s = scene.state;
  mpm::advance(s, pipeline, 0.005);
  // After a step: the grid masses and the drift are the step's (the gather ran before g2p).
  const BedLayer<dim>& bed = s.bed;
  REQUIRE(bed.particle_drift.size() == s.sediment.particles.size());
  // Along the current: the grains' flux and the layer nodes'. Per column: the layer's mass times
  // the drift speed against the formula's flux.
  double grains = 0.0, layer = 0.0, carried = 0.0, formula = 0.0;
  for (std::size_t p = 0; p < bed.particle_drift.size(); ++p)
    grains += s.sediment.particles.mass[p] * bed.particle_drift[p][0];
  std::vector<double> mass(bed.stress.size(), 0.0);
  for (const BedLayerNode<dim>& n : bed.nodes) {
    layer += s.sediment.grid.mass[n.sediment] * bed.drift[std::size_t(n.column)][0];
    mass[std::size_t(n.column)] += s.sediment.grid.mass[n.sediment];
  }
  const BedLoadLaw& law = *scene.bed_load;
  const double width = std::pow(s.sediment.grid.dx(), dim - 1);
  std::size_t capped = 0;
  for (std::size_t c = 0; c < bed.stress.size(); ++c) {
    if (!(bed.drift[c].norm() > 0.0)) continue;
    const double expected = law.sediment_density * law.morphological_factor *
                            law.flux(law.shields_number(std::sqrt(bed.stress[c].norm() / law.fluid_density))) * width;
    const double column = mass[c] * bed.drift[c].norm();
    carried += column;
    formula += expected;
    CHECK(column <= expected * (1 + 1e-12));
    if (column < expected * (1 - 1e-12)) ++capped;
  }
  MESSAGE(dim << "D, grain flux of the drift along the current: particles " << grains << ", layer nodes " << layer
              << " kg/s; over the columns " << carried << " kg/s against the formula's " << formula
              << " kg/s; largest Shields " << bed.largest_shields << ", " << capped << " columns at the speed cap");
  REQUIRE(formula > 0.0);
  CHECK(grains == doctest::Approx(layer).epsilon(1e-12));
  CHECK(carried > 0.9 * formula);
  CHECK(capped == 0);
}

}  // namespace

TEST_CASE("bed load: the formula and the wall law give the reference's flume numbers") {
  // data/reference/meyer_peter_mueller1948.md: U = 0.4 m/s over h = 0.15 m, d = 0.5 mm quartz:
  // U_f = 0.0223 m/s, theta = 0.0613, q_b = 6.1e-7 m^2/s.
  const BedLoadLaw law;
  const double u_star = law.friction_velocity(0.4, 0.15);
  CHECK(u_star == doctest::Approx(0.0223).epsilon(2e-3));
  const double theta = law.shields_number(u_star);
  CHECK(theta == doctest::Approx(0.0613).epsilon(3e-3));
  CHECK(law.flux(theta) == doctest::Approx(6.1e-7).epsilon(0.02));
  // 8 (theta - 0.047)^1.5 sqrt(1.65 g d^3) exactly, and nothing at or below the threshold.
  CHECK(law.flux(0.147) ==
        doctest::Approx(8.0 * std::pow(0.1, 1.5) * std::sqrt(1.65 * 9.81 * 1.25e-10)).epsilon(1e-12));
  CHECK(law.flux(law.critical_shields) == 0.0);
  CHECK(law.flux(0.01) == 0.0);
  CHECK(law.in_log_layer(0.15));
  CHECK_FALSE(law.in_log_layer(1e-4));
}

TEST_CASE("bed load: the layer's drag limited to the wall stress, momentum conserved") {
  // The bed's node columns x = 0.055 ... 0.345 m at dx = 5 mm (those on the sills' faces are the
  // sills'); in 3D times z = 0.005 ... 0.025 m, the 3 cm of width off the walls' layers.
  check_layer_and_limit<2>(flume("bed_load: {}"), 59);
  check_layer_and_limit<3>(flume_3d("bed_load: {}"), 59 * 5);
}

TEST_CASE("bed load: the grains' drift carries the formula's flux; the current no longer strips the bed") {
  // A threshold and a morphological factor that give a drift at this Shields number (~0.05-0.1),
  // well below the water's speed.
  const std::string transport = "bed_load: {critical_shields: 0.01, morphological_factor: 30}";
  check_drift_flux<2>(flume(transport));
  check_drift_flux<3>(flume_3d(transport));

  // 0.2 s of the current: without the closure the drag moves the top of the bed with the water;
  // with it (and no transport) the bed stays where it is.
  const auto shift_after = [&](const std::string& keys) {
    CoupledScene<2> sc = load_coupled_scene<2>(flume(keys));
    auto p = make_coupled_pipeline(sc);
    const std::vector<Vec<2>> start = sc.state.sediment.particles.x;
    mpm::advance(sc.state, p, 0.2);
    return surface_shift(sc.state, start);
  };
  const double dragged = shift_after(""), held = shift_after("bed_load: {coefficient: 1.0e-12}");
  MESSAGE("mean shift of the surface grains along the current in 0.2 s: drag alone " << dragged << " m, closure "
                                                                                     << held << " m");
  CHECK(held < 0.1 * dragged);
}

TEST_CASE("bed load: the drift stops at colliders and at the domain's closed walls") {
  CoupledScene<2> scene = load_coupled_scene<2>(flume("bed_load: {}"));
  auto pipeline = make_coupled_pipeline(scene);
  CoupledState<2>& s = scene.state;
  mpm::advance(s, pipeline, 0.005);
  const std::vector<Vec<2>> before = s.sediment.particles.x;
  // Each grain is moved by `drift` in the step, unless its target lies where `stops` says.
  const auto check_drift = [&](const Vec<2>& drift, const auto& stops) {
    s.sediment.particles.x = before;
    s.bed.particle_drift.assign(before.size(), drift / s.dt);
    stages::BedLoadDrift<2>(scene.colliders).run(s);
    std::size_t stopped = 0;
    for (std::size_t p = 0; p < before.size(); ++p) {
      const Vec<2> target = before[p] + drift;
      if (stops(target)) {
        CHECK(s.sediment.particles.x[p] == before[p]);
        ++stopped;
      } else {
        CHECK((s.sediment.particles.x[p] - target).norm() <= 1e-15);
      }
    }
    return stopped;
  };
  // 3 mm down: the bed's bottom row (0.3 m at two grains per 5 mm) would enter the floor's layer
  // (y <= 0).
  CHECK(check_drift(Vec<2>(0.0, -0.003), [](const Vec<2>& x) { return x[1] <= 0.0; }) == 120);
  // 3 mm along the current: the grains of the bed's last column (x = 0.34875 m; 0.05 m deep at
  // two grains per 5 mm) would enter the downstream sill (a box from x = 0.35, up to y = 0.07).
  CHECK(check_drift(Vec<2>(0.003, 0.0), [](const Vec<2>& x) { return x[0] >= 0.35 && x[1] <= 0.07; }) == 20);
}

TEST_CASE("bed load: the keys' errors name the key and the range") {
  const auto refuses = [](const std::string& keys, const std::string& what) {
    CHECK_THROWS_WITH_AS(load_coupled_scene<2>(flume(keys)), doctest::Contains(what.c_str()), mpm::InputError);
  };
  refuses("bed_load: {morphological_factor: 0.5}", "bed_load.morphological_factor");
  refuses("bed_load: {surface_fraction: 1.5}", "bed_load.surface_fraction");
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(flume("bed_load: {surface_fraction: 0.7}", ", packing_fraction: 0.6")),
                       doctest::Contains("below sediment.packing_fraction"), mpm::InputError);
  refuses("bed_load: {critical_shields: -0.1}", "bed_load.critical_shields");
  refuses("bed_load: {roughness: 1000}", "bed_load.roughness");
  refuses("bed_load: {exponent: 0}", "bed_load.exponent");
  const std::string dry = R"(
dim: 2
domain: {lo: [0, 0], hi: [0.22, 0.14]}
grid: {dx: 0.005}
time: {end: 1}
gravity: [0, -9.81]
sediment: {density: 2650}
bodies:
  - {phase: sediment, shape: box, lo: [0.01, 0.01], hi: [0.21, 0.06], packing_fraction: 0.6}
bed_load: {}
)";
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(mpm::Config::parse(dry)), doctest::Contains("bed_load"), mpm::InputError);
}

TEST_CASE("sediment.hold_until: the bed keeps every particle while held and moves once released") {
  // With a drift that would move the surface at once.
  CoupledScene<2> scene = load_coupled_scene<2>(
      flume("bed_load: {critical_shields: 0.01, morphological_factor: 100}", ", hold_until: 0.05"));
  auto pipeline = make_coupled_pipeline(scene);
  CoupledState<2>& s = scene.state;
  const std::vector<Vec<2>> x0 = s.sediment.particles.x;
  const std::vector<mpm::Mat<2>> F0 = mpm::solid::elastic_F(s.sediment.particles);
  mpm::advance(s, pipeline, 0.05);
  CHECK(s.sediment.particles.x == x0);
  CHECK(mpm::solid::elastic_F(s.sediment.particles) == F0);
  double fluid_speed = 0.0;
  for (const Vec<2>& v : s.fluid.particles.v) fluid_speed = std::max(fluid_speed, v.norm());
  CHECK(fluid_speed > 0.3);  // the current runs over the held bed
  mpm::advance(s, pipeline, 0.06);
  CHECK(surface_shift(s, x0) > 0.0);  // released: the drift moves the surface downstream
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(flume("", ", hold_until: -1")), doctest::Contains("sediment.hold_until"),
                       mpm::InputError);
}
