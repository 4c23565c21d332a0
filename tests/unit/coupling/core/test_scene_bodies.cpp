// Bodies of a coupled scene are seeded outside the scene's colliders (coupling/scene_loader.h):
// a pipe through the current and the bed starts empty of water and grains, the rest of both
// bodies is seeded as without it, and the inflow's section (a collider of the flow boundaries,
// not an obstacle) keeps its water. A body wholly inside a collider is refused.
#include <coupling/scene_loader.h>
#include <doctest/doctest.h>
#include <mpm/core/error.h>

#include <cmath>
#include <string>

using namespace coupling;

namespace {

//! A flume 0.4 m long, dx = 1 cm: a bed 0.1 m deep, water to 0.2 m entering at x = 0 over the
//! bed, `colliders` as given, `more_bodies` appended.
mpm::Config flume(const std::string& colliders, const std::string& more_bodies = "") {
  return mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, -0.02], hi: [0.4, 0.3]}
grid: {dx: 0.01}
time: {end: 1}
gravity: [0, -9.81]
walls: {contact: sticky, thickness: 0.02}
fluid: {density: 1000, viscosity: 1.0e-3}
pressure: {solver: mgpcg, tolerance: 1.0e-8}
drag: {law: di_felice, grain_diameter: 5.0e-4}
sediment: {density: 2650, youngs_modulus: 5.0e4, poisson_ratio: 0.3, elasticity: hencky_stvk,
           plasticity: {model: drucker_prager, friction_angle: 32}, packing_fraction: 0.6}
inflow: {face: x_min, velocity: [0.2, 0], lo: [0, 0.1], hi: [0.03, 0.2], particles_per_cell: 4}
outflow: {face: x_max}
colliders: )" + colliders + R"(
bodies:
  - {phase: sediment, shape: box, lo: [0, 0], hi: [0.4, 0.1]}
  - {phase: fluid, shape: box, lo: [0, 0], hi: [0.4, 0.2]}
)" + more_bodies);
}

//! Particles of `x` within distance r of c.
template <class Points>
std::size_t within(const Points& x, const mpm::Vec<2>& c, double r) {
  std::size_t n = 0;
  for (const mpm::Vec<2>& p : x) n += (p - c).norm() < r ? 1 : 0;
  return n;
}

}  // namespace

TEST_CASE("scene bodies: a pipe through the bed and the current starts empty; the inflow keeps its water") {
  const mpm::Vec<2> centre(0.2, 0.1);
  const double radius = 0.03;
  const CoupledScene<2> open = load_coupled_scene<2>(flume("[]"));
  const CoupledScene<2> piped =
      load_coupled_scene<2>(flume("[{type: cylinder, point: [0.2, 0.1], radius: 0.03, contact: slip}]"));
  const auto& grains = piped.state.sediment.particles.x;
  const auto& water = piped.state.fluid.particles.x;
  CHECK(within(grains, centre, radius) == 0);
  CHECK(within(water, centre, radius) == 0);
  // Without the pipe its disc holds lattice points of both bodies (4 per cell, pi r^2 / (dx^2 / 4)
  // = 113 for the whole disc): the bed's in the lower half disc, the water's in all of it.
  const std::size_t grains_in_disc = within(open.state.sediment.particles.x, centre, radius);
  const std::size_t water_in_disc = within(open.state.fluid.particles.x, centre, radius);
  CHECK(grains_in_disc > 40);
  CHECK(water_in_disc > 100);
  // Everything else is seeded as without the pipe.
  CHECK(open.state.sediment.particles.size() - grains.size() == grains_in_disc);
  CHECK(open.state.fluid.particles.size() - water.size() == water_in_disc);
  // The inflow's section (x < 0.03, 0.1 < y < 0.2) keeps its water: 3 x 10 cells of 4.
  std::size_t in_section = 0;
  for (const mpm::Vec<2>& p : water) in_section += p[0] < 0.03 && p[1] > 0.1 && p[1] < 0.2 ? 1 : 0;
  CHECK(in_section == 120);

  CHECK_THROWS_WITH_AS(
      load_coupled_scene<2>(flume("[{type: box, lo: [0.25, 0.21], hi: [0.35, 0.29], contact: sticky}]",
                                  "  - {phase: fluid, shape: box, lo: [0.26, 0.22], hi: [0.34, 0.28]}\n")),
      doctest::Contains("no particle is left"), mpm::InputError);
}
