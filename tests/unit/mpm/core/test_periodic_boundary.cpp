// Periodic axes of the core (sparse_grid.h, stages/periodic_boundary.h): P2G + fold conserves
// mass and momentum to round-off (2D, and 3D with two periodic axes) and is periodic-translation
// invariant (shifting every particle by m whole cells across the seam shifts the canonical node
// masses by m nodes, so the seam is invisible); ghosts equal their images after fold and fill;
// wrap brings particles back into [lo, hi); a uniform flow survives P2G -> G2P exactly across
// the seam; the scene key is validated.
#include <mpm/core/config.h>
#include <mpm/core/error.h>
#include <mpm/core/scene_settings.h>
#include <mpm/core/stages/periodic_boundary.h>
#include <mpm/core/transfer.h>

#include <doctest/doctest.h>

#include "random_particles.h"

using namespace mpm;

namespace {

//! Particles of `cloud` on a grid of [0, 1]^dim with dx = 1/16, periodic along `periodic`
//! (default: x only): P2G, then fold; returns the state.
template <int dim = 2>
MpmState<dim> fold(const Particles<dim>& cloud, const Kernel& kernel, std::array<bool, dim> periodic = {true}) {
  SceneSettings<dim> settings;
  settings.domain_lo = Vec<dim>::Zero();
  settings.domain_hi = Vec<dim>::Ones();
  settings.dx = 1.0 / 16;
  settings.periodic = periodic;
  settings.kernel = kernel;
  MpmState<dim> s = initial_state(settings);
  s.particles = cloud;
  sort_into_buckets(s.particles, s.kernel, s.grid, s.buckets);
  particles_to_grid(s.particles, s.buckets, s.kernel, s.transfer, s.grid);
  stages::PeriodicFold<dim>().run(s);
  return s;
}

//! Mass of canonical node (i, j) (i in [0, 16) along the periodic axis).
double canonical_mass(const SparseGrid<2>& g, int i, int j) {
  const Index k = g.node_index(g.periodic_lo() + IVec<2>(i, j));
  return k < 0 ? 0.0 : g.mass[k];
}

}  // namespace

TEST_CASE("periodic fold: conservation, translation invariance across the seam, ghosts = images") {
  for (const Kernel& kernel : {Kernel{QuadraticBSpline{}}, Kernel{CubicBSpline{}}}) {
    CAPTURE(kernel_name(kernel));
    // A cloud straddling the seam x = 0 = 1 (and one away from it).
    Particles<2> cloud = test::random_cloud<2>(400, Vec<2>(0.0, 0.3), Vec<2>(1.0, 0.7), 3);
    for (auto& x : cloud.x) x[0] = x[0] < 0.5 ? x[0] * 0.1 : 1.0 - (1.0 - x[0]) * 0.1;
    const MpmState<2> s = fold(cloud, kernel);
    const SparseGrid<2>& g = s.grid;
    double particle_mass = 0.0, canonical = 0.0;
    Vec<2> particle_momentum = Vec<2>::Zero(), grid_momentum = Vec<2>::Zero();
    for (std::size_t p = 0; p < cloud.size(); ++p) {
      particle_mass += cloud.mass[p];
      particle_momentum += cloud.mass[p] * cloud.v[p];
    }
    for (std::size_t k = 0; k < g.node_storage(); ++k) {
      const IVec<2> node = g.node_coord(k);
      const Index image = g.node_index(g.periodic_image(node));
      REQUIRE(image >= 0);
      CHECK(g.mass[k] == g.mass[image]);  // ghosts hold the folded sums too
      if (g.periodic_image(node) != node) continue;
      canonical += g.mass[k];
      grid_momentum += g.velocity[k];
    }
    CHECK(std::abs(canonical - particle_mass) <= 1e-13 * particle_mass);
    CHECK((grid_momentum - particle_momentum).norm() <= 1e-13 * particle_mass);

    // Shift by m = 5 cells and wrap: node masses shift by 5 nodes.
    Particles<2> shifted = cloud;
    for (auto& x : shifted.x) x[0] += 5.0 / 16;
    MpmState<2> wrapped = fold(cloud, kernel);
    wrapped.particles = shifted;
    stages::PeriodicWrap<2>().run(wrapped);
    for (const auto& x : wrapped.particles.x) CHECK((x[0] >= 0.0 && x[0] < 1.0));
    const MpmState<2> t = fold(wrapped.particles, kernel);
    double difference = 0.0;
    for (int i = 0; i < 16; ++i)
      for (int j = 0; j < 18; ++j)
        difference = std::max(difference, std::abs(canonical_mass(t.grid, (i + 5) % 16, j) - canonical_mass(g, i, j)));
    CHECK(difference <= 1e-12 * particle_mass);
  }
}

TEST_CASE("periodic fold in 3D (x and z periodic): conservation, ghosts = images") {
  Particles<3> cloud = test::random_cloud<3>(500, Vec<3>(0.0, 0.3, 0.0), Vec<3>(1.0, 0.7, 1.0), 9);
  const MpmState<3> s = fold<3>(cloud, QuadraticBSpline{}, {true, false, true});
  const SparseGrid<3>& g = s.grid;
  double particle_mass = 0.0, canonical = 0.0;
  Vec<3> particle_momentum = Vec<3>::Zero(), grid_momentum = Vec<3>::Zero();
  for (std::size_t p = 0; p < cloud.size(); ++p) {
    particle_mass += cloud.mass[p];
    particle_momentum += cloud.mass[p] * cloud.v[p];
  }
  for (std::size_t k = 0; k < g.node_storage(); ++k) {
    const IVec<3> node = g.node_coord(k);
    const Index image = g.node_index(g.periodic_image(node));
    REQUIRE(image >= 0);
    CHECK(g.mass[k] == g.mass[image]);
    if (g.periodic_image(node) != node) continue;
    canonical += g.mass[k];
    grid_momentum += g.velocity[k];
  }
  CHECK(std::abs(canonical - particle_mass) <= 1e-13 * particle_mass);
  CHECK((grid_momentum - particle_momentum).norm() <= 1e-13 * particle_mass);
}

TEST_CASE("periodic fill + G2P: a uniform flow crosses the seam unchanged") {
  Particles<2> cloud = test::random_cloud<2>(300, Vec<2>(0.0, 0.3), Vec<2>(1.0, 0.7), 5);
  for (auto& v : cloud.v) v = Vec<2>(0.7, -0.2);
  for (auto& C : cloud.C) C.setZero();
  MpmState<2> s = fold(cloud, QuadraticBSpline{});
  momentum_to_velocity(s.grid, s.transfer);
  stages::PeriodicFill<2>().run(s);
  s.dt = 0.1;                                    // moves every particle 0.07 in x: some cross x = 1
  const std::vector<Vec<2>> x0 = s.particles.x;  // the sort may have reordered the particles
  grid_to_particles(s.particles, s.buckets, s.kernel, s.transfer, s.grid, s.dt);
  stages::PeriodicWrap<2>().run(s);
  for (std::size_t p = 0; p < s.particles.size(); ++p) {
    CHECK((s.particles.v[p] - Vec<2>(0.7, -0.2)).norm() <= 1e-12);
    CHECK(s.particles.C[p].norm() <= 1e-10);
    double expected = x0[p][0] + 0.07;
    expected -= expected >= 1.0 ? 1.0 : 0.0;
    CHECK(std::abs(s.particles.x[p][0] - expected) <= 1e-12);
  }
}

TEST_CASE("periodic scene key: whole cells, no walls on a periodic axis") {
  const std::string base = "dim: 2\ndomain: {lo: [0, 0], hi: [1, 1]}\ngrid: {dx: 0.125}\ntime: {end: 1}\n";
  CHECK(parse_scene_settings<2>(Config::parse(base + "periodic: [true, false]\n")).periodic ==
        std::array<bool, 2>{true, false});
  CHECK(parse_scene_settings<2>(Config::parse(base)).periodic == std::array<bool, 2>{false, false});
  CHECK_THROWS_AS(parse_scene_settings<2>(Config::parse(base + "periodic: [true]\n")), InputError);
  CHECK_THROWS_AS(parse_scene_settings<2>(Config::parse(base + "periodic: [yes, no]\n")), InputError);
  const std::string uneven = "dim: 2\ndomain: {lo: [0, 0], hi: [1.05, 1]}\ngrid: {dx: 0.125}\ntime: {end: 1}\n";
  CHECK_THROWS_AS(parse_scene_settings<2>(Config::parse(uneven + "periodic: [true, false]\n")), InputError);
  CHECK_THROWS_AS(parse_scene_settings<2>(Config::parse(base + "periodic: [true, false]\nwalls: {contact: sticky}\n")),
                  InputError);
  CHECK_NOTHROW(parse_scene_settings<2>(
      Config::parse(base + "periodic: [true, false]\nwalls: {contact: sticky, x_min: open, x_max: open}\n")));
}
