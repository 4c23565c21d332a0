// Geostatic start of a sediment body (scene key `geostatic`, coupling/scene_loader.h): F^E is
// the uniaxial strain that carries the grains' buoyant overburden, the rest packing of a
// dilatant sand is the body's packing times det F^E, and a bed wall to wall under water that
// starts so stays at rest, where the same bed started stress-free consolidates and moves; a
// geostatic body with nothing below its base (a wall's layer or a collider) is refused.
#include <coupling/scene_loader.h>
#include <doctest/doctest.h>
#include <mpm/core/advance.h>
#include <mpm/core/error.h>
#include <mpm/solid/solid_channels.h>

#include <algorithm>
#include <cmath>
#include <string>

using namespace coupling;

namespace {

constexpr double kRhoS = 2500.0, kRhoF = 1010.0, kE = 5e4, kNu = 0.3, kPhi = 0.55;

//! A bed 0.2 m wide wall to wall and 0.05 m high under 0.03 m of liquid, dx = 5 mm (by default:
//! `grid`, `walls`, `colliders` as given, `more_bodies` appended to the list, `bed_keys` to the
//! bed's keys).
mpm::Config bed(bool geostatic, const std::string& grid = "{dx: 0.005}", const std::string& walls = "{contact: sticky}",
                const std::string& colliders = "[]", const std::string& more_bodies = "",
                const std::string& bed_keys = "") {
  return mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [0.22, 0.12]}
grid: )" + grid + R"(
time: {end: 1}
gravity: [0, -9.81]
colliders: )" + colliders + R"(
walls: )" + walls + R"(
fluid: {density: 1010, viscosity: 1.2e-2}
pressure: {solver: mgpcg, tolerance: 1.0e-10}
drag: {law: di_felice, grain_diameter: 2.25e-4}
sediment: {density: 2500, youngs_modulus: 5.0e4, poisson_ratio: 0.3, elasticity: hencky_stvk,
           plasticity: {model: drucker_prager, friction_angle: 28, dilatancy: 4.09, critical_packing: 0.58}}
bodies:
  - {phase: sediment, shape: box, lo: [0.01, 0.01], hi: [0.21, 0.06], packing_fraction: 0.55, geostatic: )" +
                            (geostatic ? "true" : "false") + bed_keys + R"(}
  - {phase: fluid, shape: box, lo: [0.01, 0.01], hi: [0.21, 0.09]}
)" + more_bodies);
}

//! The grains' mean speed [m/s].
double mean_speed(const CoupledState<2>& s) {
  double v = 0.0;
  for (const mpm::Vec<2>& u : s.sediment.particles.v) v += u.norm();
  return v / static_cast<double>(s.sediment.particles.size());
}

}  // namespace

TEST_CASE("geostatic start: the overburden in F^E, the packing kept, a confined bed at rest") {
  CoupledScene<2> scene = load_coupled_scene<2>(bed(true));
  mpm::Particles<2>& P = scene.state.sediment.particles;
  const std::vector<mpm::Mat<2>>& F = mpm::solid::elastic_F(P);
  const std::vector<double>* rest = mpm::solid::rest_packing(P);
  REQUIRE(rest != nullptr);
  // Particles on a lattice of spacing dx / 2 from y = 0.01125 to 0.05875: the top row's depth is
  // half a spacing, each row below one more.
  const double M = kE * (1 - kNu) / ((1 + kNu) * (1 - 2 * kNu)), top = 0.06;
  for (std::size_t p = 0; p < P.size(); ++p) {
    const double depth = top - P.x[p][1];
    CHECK(F[p](1, 1) == doctest::Approx(std::exp(-(kRhoS - kRhoF) * 9.81 * depth / M)).epsilon(1e-12));
    CHECK(F[p](0, 0) == 1.0);
    CHECK(F[p](0, 1) == 0.0);
    CHECK((*rest)[p] == doctest::Approx(kPhi * F[p].determinant()).epsilon(1e-14));  // packing phi now
  }

  // 0.1 s: started geostatic, the bed stays at rest; started stress-free, it consolidates.
  const auto speed_after = [](bool geostatic) {
    CoupledScene<2> sc = load_coupled_scene<2>(bed(geostatic));
    auto pipeline = make_coupled_pipeline(sc);
    mpm::advance(sc.state, pipeline, 0.1);
    return mean_speed(sc.state);
  };
  const double at_rest = speed_after(true), settling = speed_after(false);
  MESSAGE("mean grain speed after 0.1 s: geostatic " << at_rest << " m/s, stress-free start " << settling << " m/s");
  CHECK(at_rest < 0.3 * settling);  // measured 1.4e-5 against 7.7e-5 m/s

  // Refused without a continuum to carry the stress, and with a fluid body.
  std::string grains = R"(
dim: 2
domain: {lo: [0, 0], hi: [0.22, 0.12]}
grid: {dx: 0.005}
time: {end: 1}
gravity: [0, -9.81]
sediment: {density: 2500}
bodies:
  - {phase: sediment, shape: box, lo: [0.01, 0.01], hi: [0.21, 0.06], packing_fraction: 0.55, geostatic: true}
)";
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(mpm::Config::parse(grains)), doctest::Contains("bodies[0].geostatic"),
                       mpm::InputError);
}

TEST_CASE("geostatic start: a body that nothing holds is refused") {
  // The floor's layer is 2 dx deep by default: at dx = 2.5 mm it ends at y = 0.005, 5 mm below
  // the bed's base (a gap the bed would fall into), at dx = 5 mm at the base itself.
  CHECK_NOTHROW(load_coupled_scene<2>(bed(true)));
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(bed(true, "{dx: 0.0025}")),
                       doctest::Contains("bodies[0].geostatic' = true: a geostatic body must rest on a closed wall, a "
                                         "collider or another sediment body, but nothing holds its base at y = 0.01 m "
                                         "(the column at x = 0.010625 m)"),
                       mpm::InputError);
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(bed(true, "{dx: 0.0025}")),
                       doctest::Contains("wall layer is 0.005 m deep (walls.thickness; (support - 1) grid.dx by "
                                         "default), so its top node is at 0.005 m"),
                       mpm::InputError);
  // Held by a layer set in metres, or by a collider under the base.
  CHECK_NOTHROW(load_coupled_scene<2>(bed(true, "{dx: 0.0025}", "{contact: sticky, thickness: 0.01}")));
  CHECK_NOTHROW(load_coupled_scene<2>(
      bed(true, "{dx: 0.0025}", "{contact: sticky}", "[{type: box, lo: [0, -1], hi: [0.22, 0.01], contact: sticky}]")));
  // Or by another sediment body that rests on the floor (listed after it).
  CHECK_NOTHROW(load_coupled_scene<2>(
      bed(true, "{dx: 0.0025}", "{contact: sticky}", "[]",
          "  - {phase: sediment, shape: box, lo: [0.01, 0.005], hi: [0.21, 0.01], packing_fraction: 0.55}\n")));
  // A jittered lattice rests on the floor as well (its columns are the grid's).
  CHECK_NOTHROW(load_coupled_scene<2>(bed(true, "{dx: 0.005}", "{contact: sticky}", "[]", "", ", jitter: 0.9")));
  // A body that does not start geostatic may hang above the floor (it falls).
  CHECK_NOTHROW(load_coupled_scene<2>(bed(false, "{dx: 0.0025}")));
}
