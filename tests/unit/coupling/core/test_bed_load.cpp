// The bed-load closure (coupling/bed_load.h): the transport formula and the wall law against the
// reference's numbers, the layer's exchange limited to the wall stress with momentum conserved,
// the grains' drift carrying the formula's flux, a bed that the drag of a current no longer
// strips, the switch's suspension criterion (a grain in the current turns discrete only where
// its column's Rouse number is below the bound), and the keys' errors.
#include <coupling/bed_load.h>
#include <coupling/momentum_exchange.h>
#include <coupling/scene_loader.h>
#include <coupling/stages/bed_load.h>
#include <coupling/stages/reclassify_sediment.h>
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
  // bed_column numbers the columns as the layer does, for any point within half a spacing of
  // the column's nodes; nothing beyond the lattice.
  for (const BedLayerNode<dim>& n : layer.nodes) {
    const Vec<dim> x = s.sediment.grid.node_position(n.sediment);
    CHECK(bed_column(s.sediment.grid, 1, x) == n.column);
    CHECK(bed_column(s.sediment.grid, 1, (x + Vec<dim>::Constant(0.49 * s.sediment.grid.dx())).eval()) == n.column);
    CHECK(bed_column(s.sediment.grid, 1, (x - Vec<dim>::Constant(0.49 * s.sediment.grid.dx())).eval()) == n.column);
  }
  CHECK(bed_column(s.sediment.grid, 1, (s.sediment.grid.origin() - Vec<dim>::Constant(0.01)).eval()) == -1);
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
  // The switch's suspending stress: u_* = w_s at a Rouse number of 2.5, so for w_s = 7.29 cm/s
  // rho_w w_s^2 = 1000 * 0.0729^2 = 5.314 Pa; at P = 5, a quarter of it.
  CHECK(law.suspending_stress(0.0729, 2.5) == doctest::Approx(5.31441).epsilon(1e-12));
  CHECK(law.suspending_stress(0.0729, 5.0) == doctest::Approx(5.31441 / 4).epsilon(1e-12));
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
  refuses("bed_load: {step_length: -0.01}", "bed_load.step_length");
  refuses("bed_load: {step_length: vanrijn}", "bed_load.step_length");
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(flume("bed_load: {}", ", switching: {rouse_number: 0}")),
                       doctest::Contains("sediment.switching.rouse_number"), mpm::InputError);
  // The switch's suspension criterion asks the closure for u_*.
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(flume("", ", switching: {rouse_number: 2}")),
                       doctest::Contains("sediment.switching.rouse_number"), mpm::InputError);
  CHECK_NOTHROW(load_coupled_scene<2>(flume("", ", switching: {}")));
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

TEST_CASE("bed load and switching: the current suspends a grain only where it can") {
  // One grain (one particle) 2 cm above the bed in the current: phi_p ~ 0.05, far below phi_low.
  // 0.5 mm sand settles at 7.3 cm/s (Di Felice), so the default criterion (Rouse number 2.5)
  // needs u_* >= 7.3 cm/s (theta 0.66) in the grain's column, where this current gives about
  // 2.4 cm/s: the grain stays in the continuum. With a criterion every current meets (Rouse
  // number 1e6) it turns discrete at once.
  const std::string grain =
      "  - {phase: sediment, shape: box, lo: [0.2, 0.07], hi: [0.2025, 0.0725], packing_fraction: 0.6}\n";
  struct Result {
    bool discrete;
    mpm::Index discrete_grains;
    double stress;  // the grain's column's wall stress [Pa]
  };
  const auto after_steps = [&](const std::string& rouse) {
    CoupledScene<2> scene = load_coupled_scene<2>(flume(grain + "bed_load: {}", ", switching: {" + rouse + "}"));
    auto pipeline = make_coupled_pipeline(scene);
    const mpm::Particles<2>& P = scene.state.sediment.particles;
    const auto it = std::max_element(P.x.begin(), P.x.end(), [](auto& a, auto& b) { return a[1] < b[1]; });
    const std::size_t p = std::size_t(it - P.x.begin());
    REQUIRE(P.x[p][1] > 0.07);
    mpm::advance(scene.state, pipeline, 0.01);
    const double tau = scene.state.bed.stress[std::size_t(bed_column(scene.state.sediment.grid, 1, P.x[p]))].norm();
    MESSAGE("switching {" << rouse << "}: the grain's column's wall stress " << tau << " Pa, "
                          << count_sediment(scene.state).discrete << " discrete");
    return Result{P.material[p] == discrete_grain, count_sediment(scene.state).discrete, tau};
  };
  const Result held = after_steps("");
  CHECK_FALSE(held.discrete);
  CHECK(held.discrete_grains == 0);
  CHECK(held.stress > 0.2);  // a current over the bed, u_* of 1.4-3.2 cm/s
  CHECK(held.stress < 1.0);
  const Result lifted = after_steps("rouse_number: 1.0e6");
  CHECK(lifted.discrete);
  CHECK(lifted.discrete_grains == 1);
  // The bound itself: the grain's Rouse number P = w_s / (kappa u_*), u_* = sqrt(tau / rho_w).
  // A criterion 5 % below it keeps the grain, one 5 % above suspends it.
  const double rouse = 0.0729 / (0.4 * std::sqrt(held.stress / 1000.0));
  for (const double factor : {0.95, 1.05}) {
    CAPTURE(factor);
    const Result r = after_steps("rouse_number: " + std::to_string(factor * rouse));
    CHECK(r.stress == doctest::Approx(held.stress).epsilon(1e-3));  // the criterion leaves the flow alone
    CHECK(r.discrete == (factor > 1.0));
    CHECK(r.discrete_grains == (factor > 1.0 ? 1 : 0));
  }
}

TEST_CASE("bed load pick-up: van Rijn's saltation length") {
  // d = 0.5 mm quartz in water (nu = 1e-6 m^2/s): D* = d (1.65 g / nu^2)^(1/3) = 12.65; at theta =
  // 0.26 the transport stage T = (0.26 - 0.047) / 0.047 = 4.53 and lambda_b = 3 d D*^0.6 T^0.9 =
  // 1.5 mm x 4.58 x 3.90 = 26.8 mm (by hand).
  const BedLoadLaw law;
  CHECK(law.saltation_length(0.26) == doctest::Approx(0.0268).epsilon(0.005));
  CHECK(law.saltation_length(law.critical_shields) == 0.0);
  CHECK(law.saltation_length(0.02) == 0.0);
  BedLoadLaw fixed;
  fixed.step_length = 0.01;
  CHECK(fixed.picks_up());
  CHECK(fixed.step_length_at(0.26) == 0.01);
  CHECK_FALSE(law.picks_up());
}

TEST_CASE("bed load pick-up: past a drop of the capacity the flux decays as exp(-x / L), at first order") {
  // A row of columns along x (up = y): capacity Q up to x0, none beyond; the current along +x (and,
  // mirrored, along -x). Exactly, q(x) = Q exp(-(x - x0) / L) past x0; the upwind balance is first
  // order in dx / L.
  const double L = 0.02, Q = 3e-6;
  std::vector<double> errors;
  for (const int per_length : {4, 8, 16, 32}) {
    const double dx = L / per_length;
    const int n = 24 * per_length, drop = 16 * per_length;
    double error[2] = {0.0, 0.0};
    for (const double sign : {1.0, -1.0}) {
      std::vector<Vec<2>> capacity(std::size_t(n), Vec<2>::Zero()), direction(capacity), flux;
      const std::vector<double> length(std::size_t(n), L);
      // Mirrored: column i of the +x row is column n - 1 - i of the -x row.
      const auto column = [&](int i) { return std::size_t(sign > 0 ? i : n - 1 - i); };
      for (int i = 0; i < n; ++i) {
        direction[column(i)] = Vec<2>(sign, 0.0);
        if (i < drop) capacity[column(i)] = Vec<2>(sign * Q, 0.0);
      }
      const int sweeps = relax_to_capacity<2>(mpm::IVec<2>(n, 7), 1, dx, capacity, direction, length, flux);
      CHECK(sweeps <= 3);                   // the sweep along the current solves; the next two change nothing
      const double x0 = (drop - 0.5) * dx;  // the drop, half-way between the last column with Q and the next
      double& e = error[sign > 0 ? 0 : 1];
      for (int i = drop; i < n; ++i) {
        CHECK(flux[column(i)][1] == 0.0);
        e = std::max(e, std::abs(sign * flux[column(i)][0] - Q * std::exp(-(i * dx - x0) / L)) / Q);
      }
      // Upstream of the drop the flux has built up from nothing at the row's start: Q within 1e-6
      // after 16 L.
      CHECK(sign * flux[column(drop - 1)][0] == doctest::Approx(Q).epsilon(1e-6).scale(0));
    }
    CHECK(error[0] == doctest::Approx(error[1]).epsilon(1e-12).scale(0));
    errors.push_back(error[0]);
  }
  const double order = std::log2(errors[2] / errors[3]);
  MESSAGE("largest error over Q at dx = L/4 .. L/32: " << errors[0] << " " << errors[1] << " " << errors[2] << " "
                                                       << errors[3] << "; order " << order);
  CHECK(order > 0.9);
  CHECK(errors[3] < 0.02);
  // No step length: the formula's flux in every column.
  std::vector<Vec<2>> capacity{Vec<2>(1e-6, 0), Vec<2>(0, 0), Vec<2>(2e-6, 0)}, direction(3, Vec<2>(1, 0)), flux;
  relax_to_capacity<2>(mpm::IVec<2>(3, 5), 1, 0.01, capacity, direction, std::vector<double>(3, 0.0), flux);
  CHECK(flux == capacity);
}

TEST_CASE("bed load pick-up: 3D columns, a uniform oblique current and a circulating one") {
  // 40 x 40 columns (up = y) at dx = 5 mm, L = 1 cm. A current at 45 degrees in x-z over a uniform
  // capacity: nothing enters at the x_min and z_min edges, so the flux builds up from there, and
  // is the capacity (to 1e-5) farther than 12 L from both.
  const int n = 40;
  const double dx = 0.005;
  const mpm::IVec<3> counts(n, 9, n);
  const auto id = [&](int i, int k) { return std::size_t(k * n + i); };  // x fastest, as find_bed_layer
  const Vec<3> e = Vec<3>(1.0, 0.0, 1.0).normalized();
  std::vector<Vec<3>> capacity(std::size_t(n * n), 2e-6 * e), direction(capacity.size(), e), flux;
  std::vector<double> length(capacity.size(), 0.01);
  CHECK(relax_to_capacity<3>(counts, 1, dx, capacity, direction, length, flux) <= 8);
  CHECK(flux[id(0, 0)].norm() < 0.5 * 2e-6);
  for (int k = 25; k < n; ++k)
    for (int i = 25; i < n; ++i) CHECK((flux[id(i, k)] - 2e-6 * e).norm() < 1e-5 * 2e-6);

  // A current circling the lattice's centre, the capacity growing outwards: the columns feed each
  // other around the circle, which takes many sweeps; the result balances every column's equation
  // (checked here from its definition) to round-off.
  for (int k = 0; k < n; ++k)
    for (int i = 0; i < n; ++i) {
      const Vec<3> r((i + 0.5 - n / 2) * dx, 0.0, (k + 0.5 - n / 2) * dx);
      const Vec<3> t = Vec<3>(-r[2], 0.0, r[0]).normalized();
      direction[id(i, k)] = t;
      capacity[id(i, k)] = 1e-4 * r.norm() * t;
    }
  const int sweeps = relax_to_capacity<3>(counts, 1, dx, capacity, direction, length, flux);
  MESSAGE("circulating current: " << sweeps << " sweeps");
  CHECK(sweeps > 8);
  CHECK(sweeps < 256);
  double residual = 0.0;
  for (int k = 0; k < n; ++k)
    for (int i = 0; i < n; ++i) {
      const Vec<3>& t = direction[id(i, k)];
      const double cx = 0.01 / dx * std::abs(t[0]), cz = 0.01 / dx * std::abs(t[2]);
      const int iu = t[0] > 0 ? i - 1 : i + 1, ku = t[2] > 0 ? k - 1 : k + 1;
      Vec<3> balance = (1.0 + cx + cz) * flux[id(i, k)] - capacity[id(i, k)];
      if (iu >= 0 && iu < n && cx > 0) balance -= cx * flux[id(iu, k)];
      if (ku >= 0 && ku < n && cz > 0) balance -= cz * flux[id(i, ku)];
      residual = std::max(residual, balance.norm());
    }
  CHECK(residual < 1e-12 * 1e-4 * n * dx);
}

TEST_CASE("bed load pick-up: in the flume the flux builds up from the clear water over the sill") {
  // With a step length the first bed columns carry less than the formula (nothing comes over the
  // upstream sill), the flux reaches the formula's within a few L, and the grains' drift carries
  // the relaxed flux (the gather is still the P2G's adjoint).
  CoupledScene<2> scene =
      load_coupled_scene<2>(flume("bed_load: {critical_shields: 0.01, morphological_factor: 30, step_length: 0.01}"));
  auto pipeline = make_coupled_pipeline(scene);
  CoupledState<2>& s = scene.state;
  mpm::advance(s, pipeline, 0.005);
  const BedLayer<2>& bed = s.bed;
  const BedLoadLaw& law = *scene.bed_load;
  std::vector<double> mass(bed.stress.size(), 0.0);
  double layer = 0.0, grains = 0.0;
  for (const BedLayerNode<2>& n : bed.nodes) {
    mass[std::size_t(n.column)] += s.sediment.grid.mass[n.sediment];
    layer += s.sediment.grid.mass[n.sediment] * bed.drift[std::size_t(n.column)][0];
  }
  for (std::size_t p = 0; p < bed.particle_drift.size(); ++p)
    grains += s.sediment.particles.mass[p] * bed.particle_drift[p][0];
  CHECK(grains == doctest::Approx(layer).epsilon(1e-12).scale(0));
  std::size_t first = bed.stress.size(), building = 0, at_capacity = 0;
  for (std::size_t c = 0; c < bed.stress.size(); ++c) {
    if (!(bed.stress[c].norm() > 0.0)) continue;
    first = std::min(first, c);
    const double capacity =
        law.morphological_factor * law.flux(law.shields_number(std::sqrt(bed.stress[c].norm() / law.fluid_density)));
    // The drift carries the relaxed flux: rho_s q dx = m u_d.
    CHECK(law.sediment_density * bed.flux[c].norm() * 0.005 ==
          doctest::Approx(mass[c] * bed.drift[c].norm()).epsilon(1e-12).scale(0));
    if (c == first) CHECK(bed.flux[c].norm() < 0.5 * capacity);
    if (c < first + 4) building += bed.flux[c].norm() < 0.95 * capacity;
    if (c >= first + 20 && c < first + 40) at_capacity += std::abs(bed.flux[c].norm() / capacity - 1.0) < 0.2;
  }
  CHECK(building == 4);
  CHECK(at_capacity >= 18);
}
