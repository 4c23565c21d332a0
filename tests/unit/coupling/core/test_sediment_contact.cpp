// The sediment's own contact with a collider (collider key `sediment`, SedimentPhase::contacts):
// grains leave an obstacle whatever its contact with the water. Loaded into sediment_colliders
// only; under a sticky ceiling a hanging sand block's top is held back, with `sediment: {contact:
// separate}` it falls freely, and the water, which keeps the collider's own contact, is not
// changed by the key.
#include <coupling/scene_loader.h>
#include <doctest/doctest.h>
#include <mpm/core/advance.h>
#include <mpm/core/error.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

using namespace coupling;

namespace {

//! What hangs under the ceiling, with which solid step.
struct Setup {
  bool water = false;      //!< a water block too, beside the sand
  bool sand_hangs = true;  //!< the sand under the ceiling (the water on the floor), or the reverse
  std::string solver = "explicit";
};

//! A 0.3 x 0.3 m box, dx = 1 cm, a ceiling collider above y = 0.2 (`ceiling_keys` appended to
//! its map), a sand block 0.1 m wide (clear of the side walls' layers) and, with water, a water
//! block to its right: the one that hangs has its top at the ceiling, the other rests on the floor.
mpm::Config scene(const std::string& ceiling_keys, const Setup& setup = {}) {
  const std::string hanging = "0.1], hi: [", resting = "0.0], hi: [";
  const std::string sand = setup.sand_hangs ? "[0.04, " + hanging + "0.14, 0.2]" : "[0.04, " + resting + "0.14, 0.05]";
  const std::string water = setup.sand_hangs ? "[0.16, " + resting + "0.24, 0.05]" : "[0.16, " + hanging + "0.24, 0.2]";
  std::string text = R"(
dim: 2
domain: {lo: [0, -0.02], hi: [0.3, 0.3]}
grid: {dx: 0.01}
time: {end: 1}
gravity: [0, -9.81]
walls: {contact: sticky, thickness: 0.02}
colliders:
  - {type: box, lo: [-0.1, 0.2], hi: [0.4, 0.5], contact: sticky)" +
                     ceiling_keys + R"(}
  - {type: box, lo: [0.25, -0.1], hi: [0.4, 0.1], contact: slip}
sediment: {solver: )" +
                     setup.solver +
                     R"(, density: 2650, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk,
           plasticity: {model: drucker_prager, friction_angle: 30}}
bodies:
  - {phase: sediment, shape: box, lo: )" +
                     sand + R"(, packing_fraction: 0.6}
)";
  if (setup.water)
    text += "  - {phase: fluid, shape: box, lo: " + water + R"(}
fluid: {density: 1000, viscosity: 1.0e-3}
pressure: {solver: mgpcg, tolerance: 1.0e-10}
drag: {law: di_felice, grain_diameter: 5.0e-4}
)";
  return mpm::Config::parse(text);
}

//! The highest particle's height [m] after t seconds.
double top_after(CoupledScene<2>& sc, bool fluid, double t) {
  auto pipeline = make_coupled_pipeline(sc);
  mpm::advance(sc.state, pipeline, t);
  const auto& x = (fluid ? sc.state.fluid : sc.state.sediment).particles.x;
  double top = -1.0;
  for (const mpm::Vec<2>& p : x) top = std::max(top, p[1]);
  return top;
}

}  // namespace

TEST_CASE("sediment contact: loaded for the sediment's obstacles only") {
  const CoupledScene<2> sc = load_coupled_scene<2>(scene(", sediment: {contact: separate, friction: 0.4}"));
  REQUIRE(sc.colliders.colliders().size() == 2);
  REQUIRE(sc.sediment_colliders.colliders().size() == 2);
  CHECK(sc.colliders.colliders()[0].contact().type == mpm::geometry::ContactType::sticky);
  CHECK(sc.sediment_colliders.colliders()[0].contact().type == mpm::geometry::ContactType::separate);
  CHECK(sc.sediment_colliders.colliders()[0].contact().friction == 0.4);
  // A collider without the key meets the sediment with its own contact; the walls are the same.
  CHECK(sc.sediment_colliders.colliders()[1].contact().type == mpm::geometry::ContactType::slip);
  REQUIRE(sc.sediment_colliders.walls().has_value());
  CHECK(sc.sediment_colliders.walls()->thickness() == sc.colliders.walls()->thickness());

  // Bad input names the key: friction without separate contact, an unknown contact, and the key
  // in a scene without sediment.
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(scene(", sediment: {contact: sticky, friction: 0.4}")),
                       doctest::Contains("colliders[0].sediment.friction"), mpm::InputError);
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(scene(", sediment: {contact: glue}")),
                       doctest::Contains("colliders[0].sediment.contact"), mpm::InputError);
  const std::string water_only = R"(
dim: 2
domain: {lo: [0, 0], hi: [0.3, 0.3]}
grid: {dx: 0.01}
time: {end: 1}
gravity: [0, -9.81]
colliders: [{type: box, lo: [-0.1, 0.2], hi: [0.4, 0.5], contact: sticky, sediment: {contact: separate}}]
fluid: {density: 1000, viscosity: 1.0e-3}
bodies: [{phase: fluid, shape: box, lo: [0.1, 0.05], hi: [0.2, 0.15]}]
)";
  CHECK_THROWS_WITH_AS(load_coupled_scene<2>(mpm::Config::parse(water_only)),
                       doctest::Contains("colliders[0].sediment"), mpm::InputError);
}

TEST_CASE("sediment contact: sand leaves a ceiling that holds the water") {
  // The sticky ceiling holds the block's top row and slows the cohesionless sand below it
  // (measured 0.017 m of fall in 0.1 s explicit, 0.028 m implicit); with separate contact the
  // block falls g t^2 / 2 = 0.049 m: dry, above water (the sediment's conditions after the
  // mixture projection too) and with the implicit step, whose obstacles are its own (measured
  // 0.054 m: with its long steps symplectic Euler falls g t (t + dt) / 2).
  const double t = 0.1, free_fall = 0.5 * 9.81 * t * t;
  for (const auto& [setup, tolerance] : {std::pair{Setup{}, 0.02}, std::pair{Setup{true, true, "explicit"}, 0.02},
                                         std::pair{Setup{false, true, "implicit"}, 0.15}}) {
    CAPTURE(setup.water);
    CAPTURE(setup.solver);
    CoupledScene<2> sticky = load_coupled_scene<2>(scene("", setup));
    CoupledScene<2> separate = load_coupled_scene<2>(scene(", sediment: {contact: separate}", setup));
    const double start = top_after(sticky, false, 0.0);
    const double held = start - top_after(sticky, false, t), fallen = start - top_after(separate, false, t);
    MESSAGE("the sand's top fell " << held << " m under the sticky ceiling, " << fallen << " m with separate contact");
    CHECK(held < 0.6 * fallen);
    CHECK(fallen > free_fall);
    CHECK(fallen < (1.0 + tolerance) * free_fall);
  }

  // The water under the ceiling keeps the collider's sticky contact whatever the sand's is.
  const Setup water_hangs{true, false, "explicit"};
  CoupledScene<2> plain = load_coupled_scene<2>(scene("", water_hangs));
  CoupledScene<2> keyed = load_coupled_scene<2>(scene(", sediment: {contact: separate}", water_hangs));
  (void)top_after(plain, true, 0.05);
  (void)top_after(keyed, true, 0.05);
  CHECK(keyed.state.fluid.particles.x == plain.state.fluid.particles.x);
}
