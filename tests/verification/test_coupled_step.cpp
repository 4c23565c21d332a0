// The coupled sediment-fluid step (docs/coupling.md, "The coupled step"): the mixture
// projection with the drag in its correction conserves the mixture momentum to round-off and
// makes the mixture flux divergence-free; a dilute Stokes suspension settles at the velocity
// the drag law implies; 10 um grains at the fluid's time step stay bounded; a dry scene runs
// only the sediment stages and reproduces the solid pipeline.
#include <coupling/coupled_scene.h>
#include <coupling/scene_loader.h>
#include <coupling/settling_column.h>
#include <coupling/shared_nodes.h>
#include <coupling/stages/coupled_time_step.h>
#include <coupling/stages/exchange_stage.h>
#include <coupling/stages/mixture_projection.h>
#include <coupling/stages/on_phase.h>
#include <coupling/stages/volume_fraction_stage.h>
#include <doctest/doctest.h>
#include <fluid/stages/equation_of_state.h>
#include <mpm/core/advance.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/solid_scene.h>

#include <algorithm>
#include <cmath>
#include <string>

using namespace coupling;
using mpm::Vec;

namespace {

//! A settling column scene file with `overrides` ("key.path=value").
mpm::Config settling_scene(const std::vector<std::string>& overrides) {
  return mpm::Config::parse(R"(
dim: 2
column: {width: 0.032, height: 0.03, suspension_height: 0.02, cells_per_width: 32, particles_per_cell: 4}
fluid: {density: 1000, viscosity: 1.0e-3}
sediment: {density: 2650, volume_fraction: 0.01}
drag: {law: stokes, grain_diameter: 1.0e-4}
pressure: {solver: cg, tolerance: 1.0e-10, max_iterations: 5000}
walls: {contact: sticky}
time: {end: 0.4, frame_dt: 0.05, cfl: 0.4}
gravity: [0, -9.81]
)",
                            "settling", overrides);
}

}  // namespace

TEST_CASE("mixture projection with implicit drag: momentum to round-off, mixture flux divergence-free") {
  // A free blob of fluid with a patch of sediment, no gravity, no walls: every force is internal.
  const mpm::Config cfg = mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.0625}
time: {end: 1}
gravity: [0, 0]
)");
  mpm::SceneSettings<2> settings = mpm::parse_scene_settings<2>(cfg);
  const double rho_w = 1000.0, rho_s = 2650.0, phi = 0.3;
  SedimentPhase<2> sand;
  sand.density = rho_s;
  const drag::DragLaw law = drag::make_drag_law("schiller_naumann", {1e-3, 1e-3, rho_w});
  fluid::stages::PressureSettings pressure;
  pressure.solver = "cg";
  pressure.control.relative_tolerance = 1e-12;
  pressure.control.max_iterations = 10000;
  CoupledScene<2> scene = make_coupled_scene<2>(settings, {}, fluid::FluidMaterial{rho_w, 0.0}, pressure, sand, law);
  const double dx = settings.dx, Vp = mpm::geometry::particle_volume<2>(dx, 4);
  auto blob = mpm::geometry::seed_box<2>(Vec<2>(0.3, 0.3), Vec<2>(0.7, 0.7), dx, 4, 0.0, 1);
  for (const Vec<2>& x : blob) {
    const bool sandy = x[0] > 0.4 && x[0] < 0.6 && x[1] > 0.35 && x[1] < 0.55;
    const Vec<2> v(std::sin(9.0 * x[1]), std::cos(7.0 * x[0]));
    add_fluid_particles<2>(scene, {x}, Vp, sandy ? 1.0 - phi : 1.0, 0.3 * v, "blob");
    if (sandy) add_sediment_particles<2>(scene, {x}, phi * Vp, Vec<2>(-0.2, 0.4) + 0.1 * v, "patch");
  }

  CoupledState<2>& s = scene.state;
  using stages::OnPhase;
  using stages::Phase;
  stages::CoupledTimeStep<2> time_step({}, {});
  s.dt_limit = 2e-3;
  time_step.run(s);
  REQUIRE(s.dt == doctest::Approx(2e-3));
  for (Phase ph : {Phase::fluid, Phase::sediment}) {
    OnPhase<2>(ph, std::make_unique<mpm::stages::SortParticles<2>>()).run(s);
    OnPhase<2>(ph, std::make_unique<mpm::stages::ParticlesToGrid<2>>()).run(s);
    OnPhase<2>(ph, std::make_unique<mpm::stages::GridVelocityUpdate<2>>(false)).run(s);
  }
  stages::VolumeFractionStage<2>(rho_w, rho_s, default_min_fluid_fraction).run(s);

  auto& gw = s.fluid.grid;
  auto& gs = s.sediment.grid;
  auto node_momentum = [&] {
    Vec<2> P = Vec<2>::Zero();
    for (std::size_t k = 0; k < gw.node_storage(); ++k) P += gw.mass[k] * gw.velocity[k];
    for (std::size_t k = 0; k < gs.node_storage(); ++k) P += gs.mass[k] * gs.velocity[k];
    return P;
  };
  double scale = 0.0;  // sum of |m v|
  for (std::size_t k = 0; k < gw.node_storage(); ++k) scale += gw.mass[k] * gw.velocity[k].norm();
  for (std::size_t k = 0; k < gs.node_storage(); ++k) scale += gs.mass[k] * gs.velocity[k].norm();

  // The exchange conserves the node momentum sum m v.
  const Vec<2> before_exchange = node_momentum();
  stages::ExchangeStage<2>(law).run(s);
  CHECK((node_momentum() - before_exchange).norm() <= 1e-13 * scale);

  // The projection conserves the mixture momentum sum V (n_w rho_w v_w + n_s rho_s v_s).
  std::vector<double> n_w_fluid(gw.node_storage(), 1.0);
  for_each_shared_node(gw, gs, [&](std::size_t kw, std::size_t ks) { n_w_fluid[kw] = s.fractions.fluid[ks]; });
  const auto vw0 = gw.velocity, vs0 = gs.velocity;
  stages::MixtureProjection<2> projection(rho_w, rho_s, {}, pressure);
  projection.run(s);
  REQUIRE(projection.projection().last_result().converged);
  Vec<2> dP = Vec<2>::Zero();
  double change = 0.0;  // sum of |momentum change| per node: the scale of the pressure impulse
  for (std::size_t k = 0; k < gw.node_storage(); ++k) {
    dP += n_w_fluid[k] * rho_w * (gw.velocity[k] - vw0[k]);
    change += n_w_fluid[k] * rho_w * (gw.velocity[k] - vw0[k]).norm();
  }
  for (std::size_t k = 0; k < gs.node_storage(); ++k) {
    dP += s.fractions.sediment[k] * rho_s * (gs.velocity[k] - vs0[k]);
    change += s.fractions.sediment[k] * rho_s * (gs.velocity[k] - vs0[k]).norm();
  }
  CHECK(change > 1.0);  // the projection did act
  CHECK(dP.norm() <= 1e-12 * change);

  // D (n_w v_w + n_s v_s) = 0 in every fluid cell: the sediment share of the correction is there.
  const auto& op = projection.projection().cell_operator();
  std::vector<Vec<2>> u(static_cast<std::size_t>(op.node_count()), Vec<2>::Zero()),
      u0(static_cast<std::size_t>(op.node_count()), Vec<2>::Zero());
  for (int j = 0; j <= op.cells[1]; ++j)
    for (int i = 0; i <= op.cells[0]; ++i) {
      const mpm::IVec<2> node = projection.projection().box_origin() + mpm::IVec<2>(i, j);
      const mpm::Index kw = gw.node_index(node), ks = gs.node_index(node);
      const std::size_t b = static_cast<std::size_t>(op.node_index(mpm::IVec<2>(i, j)));
      if (kw < 0) continue;
      const double n_s = ks >= 0 ? s.fractions.sediment[ks] : 0.0;
      u[b] = (1.0 - n_s) * gw.velocity[kw];
      u0[b] = (1.0 - n_s) * vw0[kw];
      if (ks >= 0) {
        u[b] += n_s * gs.velocity[ks];
        u0[b] += n_s * vs0[ks];
      }
    }
  std::vector<double> div, div0;
  op.divergence(u, div);
  op.divergence(u0, div0);
  double worst = 0.0, initial = 0.0;
  for (std::size_t c = 0; c < div.size(); ++c) {
    worst = std::max(worst, std::abs(div[c]));
    initial = std::max(initial, std::abs(div0[c]));
  }
  CHECK(initial > 1.0);
  CHECK(worst <= 1e-8 * initial);
}

//! The settling speed [m/s, downwards] of a loaded column: the mean of mean_sediment_velocity
//! at t = 0.15, 0.2, ..., 0.4 s (the grains relax to it within a few ms).
double steady_settling_speed(SettlingScene<2>& col) {
  auto pipeline = make_coupled_pipeline(col.scene);
  CoupledState<2>& s = col.scene.state;
  mpm::advance(s, pipeline, 0.1);
  double sum = 0.0;
  int n = 0;
  for (double t = 0.15; t <= 0.4 + 1e-12; t += 0.05) {
    mpm::advance(s, pipeline, t);
    sum += mean_sediment_velocity(s, 2.0 * s.fluid.grid.dx());
    ++n;
  }
  return -sum / n;
}

TEST_CASE("dilute Stokes suspension settles at the velocity of the drag law") {
  // d = 0.1 mm, phi = 0.01, Stokes drag: v = n_w^2 v_St = 8.8 mm/s, Re = 0.9. The grain
  // relaxation time rho_s d^2 / (18 mu) = 1.5 ms; the mean is taken over 0.1 .. 0.4 s, while
  // the grains fall 3.5 mm of the 20 mm suspension.
  SettlingScene<2> col = load_settling_column<2>(settling_scene({}));
  const double v = steady_settling_speed(col), expected = col.column.hindered_velocity(),
               v_st = col.column.stokes_velocity();
  MESSAGE("settling velocity " << v << " m/s, drag law " << expected << " m/s, Stokes " << v_st << " m/s, Re "
                               << col.column.reynolds(v));
  CHECK(std::abs(expected / (0.99 * 0.99 * v_st) - 1.0) < 1e-9);
  CHECK(std::abs(v / expected - 1.0) < 0.05);
}

TEST_CASE("a weakly compressible liquid in the pores: the projection's settling speed, hydrostatic clear water") {
  // phi = 0.1, Stokes drag, 16 cells (dx = 2 mm), c = 5 m/s (the column's own compression
  // rho g h / (rho c^2) = 1.2 %): the liquid's pressure from its equation of state, shared by
  // the volume fractions (coupling/stages/pore_pressure.h), against the mixture projection.
  const std::vector<std::string> base{"sediment.volume_fraction=0.1", "column.cells_per_width=16"};
  std::vector<std::string> wc = base;
  wc.insert(wc.end(), {"fluid.solver=weakly_compressible", "fluid.speed_of_sound=5"});
  SettlingScene<2> projected = load_settling_column<2>(settling_scene(base));
  SettlingScene<2> compressible = load_settling_column<2>(settling_scene(wc));
  const auto names = make_coupled_pipeline(compressible.scene).stage_names();
  CHECK(std::find(names.begin(), names.end(), "mixture_pressure") == names.end());
  CHECK(std::find(names.begin(), names.end(), "pore_pressure_share") != names.end());
  const double v_projection = steady_settling_speed(projected), v = steady_settling_speed(compressible);
  MESSAGE("settling velocity " << v << " m/s (weakly compressible), " << v_projection << " m/s (projection), drag law "
                               << compressible.column.hindered_velocity() << " m/s");
  // With the liquid compressed by its own divergence instead of the mixture flux's it settles
  // 8.4 % fast; without the pressure share (no buoyancy) 74 % fast.
  CHECK(std::abs(v / v_projection - 1.0) < 0.05);

  // The clear water above the suspension keeps rho g (h - y) (0.03 rho g h; 0.36 when the
  // liquid's share of the volume was read from n_w at the particle instead).
  const CoupledState<2>& s = compressible.scene.state;
  const fluid::TaitEquationOfState eos{1000.0, 5.0, 7.0};
  const std::vector<double>& own = s.fluid.particles.channel<double>(fluid::kLiquidVolumeRatio);
  const double h = 0.03, rho_g = 1000.0 * 9.81;
  double worst = 0.0;
  for (std::size_t p = 0; p < own.size(); ++p)
    if (s.fluid.particles.x[p][1] > 0.02 && s.fluid.particles.x[p][1] < h - 0.004)  // below the lid's row
      worst = std::max(worst, std::abs(eos.pressure(own[p]) - rho_g * (h - s.fluid.particles.x[p][1])));
  MESSAGE("largest pressure error of the clear water at 0.4 s: " << worst / (rho_g * h) << " rho g h");
  CHECK(worst < 0.04 * rho_g * h);
}

TEST_CASE("hindered settling: the default drag law reproduces Richardson-Zaki for phi = 0.01 to 0.4") {
  // d = 0.1 mm (terminal Re 0.8, Richardson-Zaki exponent 4.38), 16 cells across. The
  // richardson_zaki law (the scene default) must settle within 10 % of n_w^n v_t at every
  // fraction; the dilute Stokes law must miss it in the dense suspensions (n_w^2 instead of
  // n_w^4.4), which shows that the comparison can fail.
  const auto settle = [](double phi, const std::string& law) {
    SettlingScene<2> col = load_settling_column<2>(settling_scene(
        {"drag.law=" + law, "sediment.volume_fraction=" + std::to_string(phi), "column.cells_per_width=16"}));
    return std::pair{steady_settling_speed(col), col.column.richardson_zaki_velocity()};
  };
  for (const double phi : {0.01, 0.1, 0.2, 0.3, 0.4}) {
    const auto [v, v_rz] = settle(phi, "richardson_zaki");
    MESSAGE("phi " << phi << ": settling " << v << " m/s, Richardson-Zaki " << v_rz << " m/s");
    CHECK(std::abs(v / v_rz - 1.0) < 0.10);
  }
  const auto [v, v_rz] = settle(0.3, "stokes");
  MESSAGE("stokes drag, phi 0.3: settling " << v << " m/s, Richardson-Zaki " << v_rz << " m/s");
  CHECK(v > 1.5 * v_rz);
}

TEST_CASE("a slip-dependent drag law settles at the same speed for any time step") {
  // Schiller-Naumann (beta grows with the slip), phi = 0.1, 16 cells: the steady state of the
  // step must be the law's whatever dt. The mixture projection once evaluated beta again at
  // the slip the exchange had relaxed (a sixth of it at the fluid's step): the grains then
  // settled 5.5 % faster at the default step than at a twentieth of it (now 1 %).
  const auto settle = [](const std::string& max_dt) {
    SettlingScene<2> col =
        load_settling_column<2>(settling_scene({"drag.law=schiller_naumann", "sediment.volume_fraction=0.1",
                                                "column.cells_per_width=16", "time.max_dt=" + max_dt}));
    const double v = steady_settling_speed(col);
    const CoupledState<2>& s = col.scene.state;
    return std::pair{v, s.time / static_cast<double>(s.step)};  // the mean step
  };
  const auto [v_large, dt_large] = settle("1");
  const auto [v_small, dt_small] = settle("2.5e-4");
  MESSAGE("settling " << v_large << " m/s at dt " << dt_large << " s, " << v_small << " m/s at dt " << dt_small
                      << " s");
  REQUIRE(dt_large > 10.0 * dt_small);
  CHECK(std::abs(v_large / v_small - 1.0) < 0.025);
}

TEST_CASE("the settling column is closed: a periodic axis is refused with its key") {
  const std::vector<std::string> open_sides = {"walls.x_min=open", "walls.x_max=open", "periodic=[true, false]"};
  CHECK_THROWS_WITH_AS(load_settling_column<2>(settling_scene(open_sides)),
                       doctest::Contains("key 'periodic' = [true, false]: the settling column is closed"),
                       mpm::InputError);
}

TEST_CASE("stiff drag: 10 um grains at the fluid's time step stay bounded and hindered") {
  // d = 10 um: relaxation time 15 us, a thousandth of the fluid's step. phi = 0.2 with
  // Schiller-Naumann (Stokes limit at Re = 1e-6): v = n_w^2 v_St = 0.64 v_St.
  SettlingScene<2> col = load_settling_column<2>(
      settling_scene({"drag.grain_diameter=1.0e-5", "sediment.volume_fraction=0.2", "drag.law=schiller_naumann",
                      "column.width=0.008", "column.cells_per_width=8"}));
  auto pipeline = make_coupled_pipeline(col.scene);
  CoupledState<2>& s = col.scene.state;
  const double dx = s.fluid.grid.dx(), v_st = col.column.stokes_velocity();
  double sum = 0.0;
  int n = 0;
  for (double t = 0.05; t <= 0.3 + 1e-12; t += 0.05) {
    mpm::advance(s, pipeline, t);
    double fastest_grain = 0.0, fastest_fluid = 0.0, slip = 0.0;
    for (const auto& v : s.sediment.particles.v) {
      REQUIRE(std::isfinite(v.squaredNorm()));
      fastest_grain = std::max(fastest_grain, v.norm());
    }
    for (const auto& v : s.fluid.particles.v) fastest_fluid = std::max(fastest_fluid, v.norm());
    // The end-of-step slip inside the suspension: bounded by the terminal velocity.
    const auto& gw = s.fluid.grid;
    const auto& gs = s.sediment.grid;
    for_each_shared_node(gw, gs, [&](std::size_t kw, std::size_t ks) {
      if (gw.mass[kw] > 0.0 && s.fractions.sediment[ks] > 0.1)
        slip = std::max(slip, (gs.velocity[ks] - gw.velocity[kw]).norm());
    });
    CHECK(s.dt > 1e2 * 1.5e-5);
    CHECK(slip <= v_st);
    CHECK(fastest_grain <= fastest_fluid + v_st);  // the grains go with the fluid
    if (t > 0.1) {
      sum += mean_sediment_velocity(s, 2.0 * dx);
      ++n;
    }
  }
  const double v = -sum / n, expected = col.column.hindered_velocity();
  MESSAGE("stiff drag: settling velocity " << v << " m/s, drag law " << expected << " m/s, Stokes " << v_st
                                           << " m/s, dt " << s.dt << " s");
  CHECK(std::abs(expected / (0.8 * 0.8 * v_st) - 1.0) < 1e-3);
  CHECK(std::abs(v / expected - 1.0) < 0.10);
}

TEST_CASE("dry scene: only the sediment stages, no fluid grid, the solid pipeline reproduced") {
  const mpm::Config cfg = mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [0.4, 0.3]}
grid: {dx: 0.01}
materials:
  - name: sand
    density: 2650
    youngs_modulus: 3.0e6
    poisson_ratio: 0.3
    elasticity: hencky_stvk
    plasticity: {model: drucker_prager, friction_angle: 32, cohesion: 0}
bodies:
  - {shape: box, lo: [0.02, 0.02], hi: [0.12, 0.2], material: sand}
walls: {contact: separate, y_min: sticky}
time: {end: 1, cfl: 0.4}
gravity: [0, -9.81]
)");
  mpm::solid::SolidScene<2> solid = mpm::solid::load_solid_scene<2>(cfg);
  auto solid_pipeline = mpm::solid::make_solid_pipeline(solid);
  SedimentPhase<2> sand;
  sand.density = 2650.0;
  sand.solver = "explicit";
  sand.materials = solid.materials;
  CoupledScene<2> dry = make_coupled_scene<2>(solid.settings, solid.colliders, std::nullopt, {}, sand, std::nullopt);
  dry.state.sediment.particles = solid.state.particles;
  auto pipeline = make_coupled_pipeline(dry);
  for (const std::string& name : pipeline.stage_names())
    CHECK_MESSAGE((name == "time_step" || name.rfind("sediment.", 0) == 0), "stage " << name);
  for (int step = 0; step < 40; ++step) {
    pipeline.step(dry.state);
    dry.state.time += dry.state.dt;
    solid_pipeline.step(solid.state);
    solid.state.time += solid.state.dt;
  }
  CHECK(dry.state.fluid.grid.node_storage() == 0);
  CHECK(dry.state.dt == solid.state.dt);
  double moved = 0.0, differ = 0.0;
  for (std::size_t p = 0; p < solid.state.particles.size(); ++p) {
    moved = std::max(moved, solid.state.particles.v[p].norm());
    differ = std::max(differ, (dry.state.sediment.particles.x[p] - solid.state.particles.x[p]).norm());
  }
  CHECK(moved > 0.0);
  CHECK(differ == 0.0);
}

TEST_CASE("one coupled scene, two sediment solvers x two pressure solvers: the same bookkeeping for each") {
  // A free blob of water holding a patch of sand, no gravity and no walls: each phase keeps its
  // mass exactly, and swapping the pressure back-end changes the state only by the solver
  // tolerance, whichever solid solver moves the sand. (The particles' momentum is not a check
  // here: the projection of a free surface does not conserve it, see the test above for the
  // mixture momentum the projection does conserve.)
  const Vec<2> patch_velocity(-0.2, 0.4);
  for (const std::string solid : {"explicit", "grains"}) {
    std::vector<std::vector<Vec<2>>> velocities;
    for (const std::string pressure_solver : {"mgpcg", "cg"}) {
      CAPTURE(solid);
      CAPTURE(pressure_solver);
      const std::string material = solid == "explicit"
                                       ? ", youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk, "
                                         "plasticity: {model: drucker_prager, friction_angle: 30}"
                                       : "";
      const mpm::Config cfg = mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.0625}
time: {end: 1, cfl: 0.4, max_dt: 0.005}
gravity: [0, 0]
pressure: {solver: )" + pressure_solver + R"(, tolerance: 1.0e-10, max_iterations: 10000}
sediment: {solver: )" + solid + ", density: 2650" +
                                                 material + "}\n");
      const mpm::SceneSettings<2> settings = mpm::parse_scene_settings<2>(cfg);
      const SedimentPhase<2> sand = parse_sediment_phase<2>(cfg.child("sediment"));
      const drag::DragLaw law = drag::make_drag_law("schiller_naumann", {1e-3, 1e-3, 1000.0});
      CoupledScene<2> scene = make_coupled_scene<2>(settings, {}, fluid::FluidMaterial{1000.0, 0.0},
                                                    fluid::parse_pressure_settings(cfg), sand, law);
      REQUIRE(scene.solid_solver->name() == solid);
      const double dx = settings.dx, Vp = mpm::geometry::particle_volume<2>(dx, 4), phi = 0.3;
      for (const Vec<2>& x : mpm::geometry::seed_box<2>(Vec<2>(0.3, 0.3), Vec<2>(0.7, 0.7), dx, 4, 0.0, 1)) {
        const bool sandy = x[0] > 0.4 && x[0] < 0.6 && x[1] > 0.35 && x[1] < 0.55;
        const Vec<2> v(std::sin(9.0 * x[1]), std::cos(7.0 * x[0]));
        add_fluid_particles<2>(scene, {x}, Vp, sandy ? 1.0 - phi : 1.0, 0.3 * v, "blob");
        if (sandy) add_sediment_particles<2>(scene, {x}, phi * Vp, patch_velocity + 0.1 * v, "patch");
      }
      auto pipeline = make_coupled_pipeline(scene);
      const auto names = pipeline.stage_names();
      const bool has_stress = std::find(names.begin(), names.end(), "sediment.p2g_stress") != names.end();
      CHECK(has_stress == (solid == "explicit"));

      CoupledState<2>& s = scene.state;
      const double mw0 = s.fluid.particles.total_mass(), ms0 = s.sediment.particles.total_mass();
      mpm::advance(s, pipeline, 0.05);
      CHECK(s.step >= 10);
      CHECK(s.fluid.particles.total_mass() == mw0);
      CHECK(s.sediment.particles.total_mass() == ms0);
      // The pressure stage reports its last solve through the pipeline's diagnostics.
      for (const mpm::Diagnostic& d : pipeline.diagnostics())
        if (d.name == "pressure_residual") CHECK(d.value <= 1e-9);
      // The step moved the sand relative to the water: the drag and the pressure acted.
      double slip = 0;
      for (const Vec<2>& v : s.sediment.particles.v) slip += (v - patch_velocity).norm();
      CHECK(slip > 0.0);
      std::vector<Vec<2>> v = s.fluid.particles.v;
      v.insert(v.end(), s.sediment.particles.v.begin(), s.sediment.particles.v.end());
      velocities.push_back(v);
    }
    REQUIRE(velocities[0].size() == velocities[1].size());
    double difference = 0.0;
    for (std::size_t p = 0; p < velocities[0].size(); ++p)
      difference = std::max(difference, (velocities[0][p] - velocities[1][p]).norm());
    CAPTURE(solid);
    CHECK(difference < 1e-6);
  }
}

TEST_CASE(
    "a clear-fluid coupled scene runs either fluid solver with the same bookkeeping; a sediment needs "
    "an incompressible one") {
  // A square blob of water squeezed towards its centre while it falls, far from every wall: the
  // pressure forces are internal, so the mass holds exactly and the momentum grows by M g t.
  for (const std::string solver : {"projection", "weakly_compressible"}) {
    CAPTURE(solver);
    const mpm::Config cfg = mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.03125}
time: {end: 1, cfl: 0.4}
gravity: [0, -9.81]
fluid: {density: 1000, viscosity: 0, solver: )" +
                                               solver + "}\n");
    const mpm::SceneSettings<2> settings = mpm::parse_scene_settings<2>(cfg);
    CoupledScene<2> scene = make_coupled_scene<2>(settings, {}, fluid::parse_fluid_material(cfg.child("fluid")),
                                                  fluid::parse_pressure_settings(cfg), std::nullopt, std::nullopt,
                                                  fluid::parse_fluid_solver(cfg.child("fluid")));
    REQUIRE(scene.fluid_solver->name() == solver);
    const Vec<2> centre(0.5, 0.6);
    const double dx = settings.dx, Vp = mpm::geometry::particle_volume<2>(dx, 4);
    for (const Vec<2>& x : mpm::geometry::seed_box<2>(Vec<2>(0.4, 0.5), Vec<2>(0.6, 0.7), dx, 4, 0.0, 1))
      add_fluid_particles<2>(scene, {x}, Vp, 1.0, -0.5 * (x - centre), "blob");
    auto pipeline = make_coupled_pipeline(scene);
    CoupledState<2>& s = scene.state;
    const mpm::Particles<2>& P = s.fluid.particles;
    auto momentum = [&] {
      Vec<2> sum = Vec<2>::Zero();
      for (std::size_t p = 0; p < P.size(); ++p) sum += P.mass[p] * P.v[p];
      return sum;
    };
    const double mass = P.total_mass();
    const Vec<2> before = momentum();
    mpm::advance(s, pipeline, 0.05);
    double scale = 0.0;
    for (std::size_t p = 0; p < P.size(); ++p) scale += P.mass[p] * P.v[p].norm();
    CHECK(P.total_mass() == mass);
    // The weakly compressible pressure is a particle stress, whose grid forces sum to zero: the
    // momentum holds to round-off. The projection conserves sum V rho v over the nodes (the
    // mixture test above), not sum m v: its impulse per unit volume is the same on surface nodes
    // that hold less mass, and the surface extension then moves the loose nodes above the
    // surface (those no fluid cell has as a corner) with their neighbours. A blob that is not
    // symmetric on the grid drifts: measured 0.45 % of sum m |v| here (0.30 % with
    // pressure.surface_extension off), bounded at 1 %.
    const double drift = (momentum() - before - mass * 0.05 * settings.gravity).norm();
    CHECK(drift <= (solver == "projection" ? 1e-2 : 1e-12) * scale);
    // The pressure acted: the projection solved, or the squeezed liquid changed volume.
    for (const mpm::Diagnostic& d : pipeline.diagnostics())
      if (d.name == "pressure_iterations") CHECK(d.value > 0.0);
    if (const auto* J = P.find_channel<double>(fluid::kVolumeRatio)) {
      double change = 0.0;
      for (const double j : *J) change = std::max(change, std::abs(j - 1.0));
      CHECK(change > 1e-3);
    }
  }
  const mpm::Config sandy = mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.0625}
time: {end: 1}
fluid: {density: 1000, viscosity: 1.0e-3, solver: weakly_compressible}
sediment: {density: 2650}
)");
  // Beside a sediment the weakly compressible liquid carries the pore pressure itself
  // (coupling/stages/pore_pressure.h): no mixture projection, the liquid volume ratio checkpointed.
  const CoupledScene<2> wet_sand = make_coupled_scene<2>(
      mpm::parse_scene_settings<2>(sandy), {}, fluid::parse_fluid_material(sandy.child("fluid")), {},
      parse_sediment_phase<2>(sandy.child("sediment")), drag::make_drag_law("stokes", {1e-4, 1e-3, 1000.0}),
      fluid::parse_fluid_solver(sandy.child("fluid")));
  CHECK(wet_sand.state.fluid.particles.has_channel(fluid::kLiquidVolumeRatio));
  const auto names = make_coupled_pipeline(wet_sand).stage_names();
  for (const char* stage : {"pore_pressure_share", "liquid_volume"})
    CHECK(std::find(names.begin(), names.end(), stage) != names.end());
  CHECK(std::find(names.begin(), names.end(), "mixture_pressure") == names.end());

  // A wet sand blob in free fall, squeezed: the pore pressure and the drag only move momentum
  // between the phases and the nodes, so the total changes by the weight alone.
  CoupledScene<2> blob = wet_sand;
  const double dx = blob.settings.dx, Vp = mpm::geometry::particle_volume<2>(dx, 4);
  const Vec<2> centre(0.5, 0.6);
  for (const Vec<2>& x : mpm::geometry::seed_box<2>(Vec<2>(0.4, 0.5), Vec<2>(0.6, 0.7), dx, 4, 0.0, 1)) {
    add_fluid_particles<2>(blob, {x}, Vp, 0.6, -0.5 * (x - centre), "blob");
    add_sediment_particles<2>(blob, {x}, 0.4 * Vp, 0.3 * (x - centre), "blob");
  }
  auto pipeline = make_coupled_pipeline(blob);
  CoupledState<2>& s = blob.state;
  const auto momentum = [&] {
    Vec<2> sum = Vec<2>::Zero();
    for (const mpm::Particles<2>* P : {&s.fluid.particles, &s.sediment.particles})
      for (std::size_t p = 0; p < P->size(); ++p) sum += P->mass[p] * P->v[p];
    return sum;
  };
  const double mass = s.fluid.particles.total_mass() + s.sediment.particles.total_mass();
  const Vec<2> before = momentum();
  mpm::advance(s, pipeline, 0.05);
  double scale = 0.0;
  for (const mpm::Particles<2>* P : {&s.fluid.particles, &s.sediment.particles})
    for (std::size_t p = 0; p < P->size(); ++p) scale += P->mass[p] * P->v[p].norm();
  // Measured 3.4e-11 of sum m |v| after 33 steps (the same blob under the mixture projection
  // drifts by 3.9e-5, its surface extension not being momentum-neutral).
  CHECK((momentum() - before - mass * 0.05 * blob.settings.gravity).norm() <= 1e-9 * scale);
  double change = 0.0;  // the liquid was squeezed: its own volume changed
  for (const double r : s.fluid.particles.channel<double>(fluid::kLiquidVolumeRatio))
    change = std::max(change, std::abs(r - 1.0));
  CHECK(change > 1e-4);
}
