// The NaN/Inf guard (core/finite_guard.h) and the stages that run it: a non-finite value
// planted in one particle (or in the grid nodes of one particle's stencil) must stop the stage
// with a NumericalError that names the stage, that particle's index and the quantity.
#include <mpm/core/finite_guard.h>
#include <mpm/core/stages/grid_to_particles.h>
#include <mpm/core/stages/grid_velocity_update.h>
#include <mpm/core/stages/particles_to_grid.h>
#include <mpm/core/stages/sort_particles.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>
#include <mpm/solid/stages/return_map.h>
#include <mpm/solid/stages/stress_forces.h>

#include <doctest/doctest.h>

#include <limits>
#include <string>
#include <vector>

using namespace mpm;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

//! The message of the NumericalError `run` throws ("" when it throws none).
template <class F>
std::string numerical_error(F&& run) {
  try {
    run();
  } catch (const NumericalError& e) {
    return e.what();
  }
  return "";
}

//! A moving elastic block in [0.2, 0.4]^2 and one particle alone at (0.8, 0.8), sorted, with
//! grid velocities after P2G and forces: the state the deformation, stress and G2P stages read.
struct Scene {
  solid::SolidScene<2> solid;
  std::size_t lone = 0;  //!< index of the lone particle after the sort

  explicit Scene(const std::string& material = "{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3}")
      : solid(make(material)) {
    MpmState<2>& s = solid.state;
    s.dt = 1e-4;
    stages::SortParticles<2>().run(s);
    stages::ParticlesToGrid<2>().run(s);
    stages::StressForces<2>(solid.materials).run(s);
    stages::GridVelocityUpdate<2>(true).run(s);
    while (s.particles.x[lone][0] < 0.7) ++lone;
  }

  static solid::SolidScene<2> make(const std::string& material_yaml) {
    SceneSettings<2> settings;
    settings.domain_lo = Vec<2>::Zero();
    settings.domain_hi = Vec<2>::Ones();
    settings.dx = 0.05;
    settings.kernel = QuadraticBSpline{};
    settings.gravity = Vec<2>(0.0, -9.81);
    const Config material = Config::parse(material_yaml);
    auto scene = solid::make_solid_scene<2>(settings, {parse_material<2>(material)}, {});
    const double volume = geometry::particle_volume<2>(settings.dx, 4);
    solid::add_particles<2>(scene,
                            geometry::seed_box<2>(Vec<2>::Constant(0.2), Vec<2>::Constant(0.4), settings.dx, 4, 0.0, 1),
                            volume, 0, Vec<2>(0.5, 0.1), "block");
    solid::add_particles<2>(scene, {Vec<2>::Constant(0.8)}, volume, 0, Vec<2>::Zero(), "lone");
    return scene;
  }
};

}  // namespace

TEST_CASE("check_finite names the first non-finite entry") {
  std::vector<Vec<2>> v(6, Vec<2>::Ones());
  CHECK_NOTHROW(check_finite(v, "g2p", "particle", "velocity"));
  v[4][1] = kInf;
  v[3][0] = kNaN;
  CHECK(numerical_error([&] { check_finite(v, "g2p", "particle", "velocity"); }) ==
        "stage 'g2p': particle 3 has non-finite velocity");
  std::vector<double> m(3, 1.0);
  m[2] = -kInf;
  CHECK(numerical_error([&] { check_finite(m, "p2g", "node", "mass"); }) == "stage 'p2g': node 2 has non-finite mass");
}

TEST_CASE("the prepared state is finite, so each stage below fails only for the planted value") {
  Scene scene;
  MpmState<2>& s = scene.solid.state;
  REQUIRE(s.particles.size() > 1);
  CHECK(s.particles.x[scene.lone] == Vec<2>::Constant(0.8));
  for (const Vec<2>& v : s.grid.velocity) CHECK(v.allFinite());
  CHECK(numerical_error([&] { stages::GridToParticles<2>(solid::kElasticF).run(s); }).empty());
  Scene fresh;  // the first g2p advected the particles away from their buckets
  CHECK(numerical_error([&] { stages::GridToParticles<2>().run(fresh.solid.state); }).empty());
}

TEST_CASE("a non-finite F stops 'stress_forces' and 'g2p' (the deformation update) naming the particle") {
  for (const double bad : {kNaN, kInf}) {
    Scene scene;
    MpmState<2>& s = scene.solid.state;
    const std::size_t p = s.particles.size() / 2;
    solid::elastic_F(s.particles)[p](1, 0) = bad;
    const std::string expected = "particle " + std::to_string(p) + " has non-finite ";
    CHECK(numerical_error([&] { stages::StressForces<2>(scene.solid.materials).run(s); }) ==
          "stage 'stress_forces': " + expected + "Kirchhoff stress");
    CHECK(numerical_error([&] { stages::GridToParticles<2>(solid::kElasticF).run(s); }) ==
          "stage 'g2p': " + expected + "deformation gradient F");
  }
}

TEST_CASE("a non-finite cached stress stops the fused 'p2g_stress' (all materials plastic) naming the particle") {
  // Every particle of a plastic material carries the return map's stress, which the fused
  // scatter reads in place (ParticleStress): an entry is tested where the stage meets it. An
  // entry NaN in its first coefficient reads as unknown and is recomputed from F^E.
  for (const double bad : {kNaN, kInf}) {
    Scene scene(
        "{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk,"
        " plasticity: {model: von_mises, yield_stress: 1e3}}");
    MpmState<2>& s = scene.solid.state;
    using Fused = stages::StressForces<2>;
    Fused p2g_stress(scene.solid.materials, false, Fused::Scatter::with_momentum);
    std::vector<Mat<2>>& cache = *solid::stress_cache(s.particles);
    for (Mat<2>& tau : cache) CHECK_FALSE(solid::known_stress(tau));
    CHECK(numerical_error([&] { p2g_stress.run(s); }).empty());  // the unknown entries filled in place
    for (const Mat<2>& tau : cache) REQUIRE(solid::known_stress(tau));
    const std::size_t p = s.particles.size() / 2;
    cache[p](1, 0) = bad;
    CHECK(numerical_error([&] { p2g_stress.run(s); }) ==
          "stage 'p2g_stress': particle " + std::to_string(p) + " has non-finite Kirchhoff stress");
    cache[p].setConstant(kNaN);  // unknown: recomputed
    CHECK(numerical_error([&] { p2g_stress.run(s); }).empty());
    CHECK(cache[p].allFinite());
  }
}

TEST_CASE("a non-finite grid velocity stops 'g2p' naming the particle that gathers it") {
  Scene scene;
  MpmState<2>& s = scene.solid.state;
  // Only the lone particle's stencil (3 x 3 nodes within 1.5 dx) reaches these nodes.
  const Vec<2> x = s.particles.x[scene.lone];
  for (std::size_t k = 0; k < s.grid.node_storage(); ++k)
    if ((s.grid.node_position(k) - x).lpNorm<Eigen::Infinity>() <= 1.5 * s.grid.dx())
      s.grid.velocity[k] = Vec<2>(kNaN, 0.0);
  CHECK(numerical_error([&] { stages::GridToParticles<2>().run(s); }) ==
        "stage 'g2p': particle " + std::to_string(scene.lone) + " has non-finite velocity");
}

TEST_CASE("all_finite finds one NaN or infinity anywhere in short and long arrays (the parallel blocks)") {
  constexpr double kLargest = std::numeric_limits<double>::max();
  constexpr double kSubnormal = std::numeric_limits<double>::denorm_min();
  for (const std::size_t n : {std::size_t{1}, std::size_t{7}, std::size_t{1000}, std::size_t{300001}}) {
    std::vector<double> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = (i % 3 == 0 ? kLargest : i % 3 == 1 ? -kSubnormal : -0.0);
    CHECK(all_finite(v.data(), n));
    for (const std::size_t at : {std::size_t{0}, n / 2, n - 1})
      for (const double bad : {kNaN, kInf, -kInf}) {
        CAPTURE(n);
        CAPTURE(at);
        const double kept = v[at];
        v[at] = bad;
        CHECK_FALSE(all_finite(v.data(), n));
        v[at] = kept;
      }
  }
  CHECK(all_finite(nullptr, 0));
  // Through check_finite: vectors of Eigen matrices are checked as their doubles.
  std::vector<Mat<3>> F(50000, Mat<3>::Identity());
  F[49999](2, 1) = kNaN;
  CHECK(numerical_error([&] { check_finite(F, "g2p", "particle", "F"); }) ==
        "stage 'g2p': particle 49999 has non-finite F");
}

TEST_CASE("g2p_plasticity names a non-finite F of its gather as g2p's; an empty channel passes") {
  const Config sand = Config::parse(
      "{density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: hencky_stvk, plasticity: {model: "
      "drucker_prager, "
      "friction_angle: 30}}");
  Scene scene;
  MpmState<2>& s = scene.solid.state;
  const std::size_t p = s.particles.size() / 2;
  solid::elastic_F(s.particles)[p](0, 1) = kNaN;
  stages::GridToParticles<2> fused(solid::kElasticF,
                                   std::make_unique<stages::ReturnMap<2>>(std::vector{parse_material<2>(sand)}));
  CHECK(fused.name() == "g2p_plasticity");
  CHECK(numerical_error([&] { fused.run(s); }) ==
        "stage 'g2p_plasticity': particle " + std::to_string(p) + " has non-finite deformation gradient F");
  Scene fresh;
  CHECK(numerical_error([&] { fused.run(fresh.solid.state); }).empty());
  const std::vector<Mat<3>> none;
  CHECK_NOTHROW(check_finite(none, "g2p", "particle", "F"));
}
