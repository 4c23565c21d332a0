// The fluid pipeline on periodic axes: a 3D fully periodic shear flow u = U sin(k y) e_x (an
// exact Navier-Stokes solution with constant pressure, decaying as e^{-nu k^2 t}) keeps its
// shape and decays at the exact rate; it is discretely divergence-free, so its right-hand side
// is round-off, which the projection must absorb (the 3D periodic NodeCell operator has null
// vectors beyond the constants); the pipeline holds the three periodic stages.
#include <fluid/scene/fluid_scene.h>

#include <mpm/core/advance.h>
#include <mpm/geometry/seeding.h>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

using namespace mpm;

TEST_CASE("3D periodic shear flow decays at the exact viscous rate") {
  const int n = 16;
  const double L = 2.0 * std::numbers::pi, dx = L / n, nu = 0.1, dt = 0.02;
  SceneSettings<3> settings;
  settings.domain_lo = Vec<3>::Zero();
  settings.domain_hi = Vec<3>::Constant(L);
  settings.dx = dx;
  settings.periodic = {true, true, true};
  settings.gravity = Vec<3>::Zero();
  fluid::FluidScene<3> scene = fluid::make_fluid_scene<3>(settings, {1.0, nu}, {}, {});
  fluid::add_fluid_particles<3>(scene, geometry::seed_box<3>(Vec<3>::Zero(), Vec<3>::Constant(L), dx, 8, 0.0, 1),
                                geometry::particle_volume<3>(dx, 8), Vec<3>::Zero(), "shear");
  Particles<3>& P = scene.state.particles;
  for (std::size_t p = 0; p < P.size(); ++p) {
    P.v[p] = Vec<3>(std::sin(P.x[p][1]), 0.0, 0.0);
    P.C[p].setZero();
    P.C[p](0, 1) = std::cos(P.x[p][1]);
  }
  auto pipeline = fluid::make_fluid_pipeline(scene);
  const std::vector<std::string> names = pipeline.stage_names();
  for (const std::string stage : {"periodic_fold", "periodic_fill", "periodic_wrap"}) {
    CAPTURE(stage);
    CHECK(std::find(names.begin(), names.end(), stage) != names.end());
  }
  for (int step = 0; step < 20; ++step) mpm::step_towards(scene.state, pipeline, scene.state.time + dt);
  const double decay = std::exp(-nu * scene.state.time);
  double error = 0.0, norm = 0.0;
  for (std::size_t p = 0; p < P.size(); ++p) {
    const Vec<3> exact(std::sin(P.x[p][1]) * decay, 0.0, 0.0);
    error += (P.v[p] - exact).squaredNorm();
    norm += exact.squaredNorm();
    CHECK((P.x[p].array() >= 0.0).all());
    CHECK((P.x[p].array() < L).all());
  }
  CHECK(scene.state.time == doctest::Approx(20 * dt));
  CHECK(std::sqrt(error / norm) <= 0.02);  // measured 0.013
}

TEST_CASE("a weakly compressible liquid refuses periodic axes (its forces are not folded)") {
  SceneSettings<2> settings;
  settings.domain_lo = Vec<2>::Zero();
  settings.domain_hi = Vec<2>::Ones();
  settings.dx = 0.125;
  settings.periodic = {true, false};
  fluid::FluidSolverSettings solver;
  solver.name = "weakly_compressible";
  CHECK_THROWS_WITH_AS(fluid::make_fluid_scene<2>(settings, {1000.0, 0.0}, {}, {}, solver),
                       doctest::Contains("has no periodic axes"), InputError);
  CHECK_NOTHROW(fluid::make_fluid_scene<2>(settings, {1000.0, 0.0}, {}, {}));
}
