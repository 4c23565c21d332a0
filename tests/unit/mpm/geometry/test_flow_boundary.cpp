// Particle removal and emission: erase_flagged is a stable compaction of every channel; the
// source emits floor((|v_a| t + delta) / h) lattice layers, on the moving lattice, within one
// layer of rho |v_a| A t, whatever the step sizes; a stream through a sink keeps mass in = out +
// stored to round-off; the inflow/outflow keys open their faces, prescribe the inlet velocity
// and reject closed or inconsistent faces.
#include <mpm/core/error.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/flow_boundary_config.h>

#include <doctest/doctest.h>

#include <cmath>
#include <string>

using namespace mpm;

namespace {

template <int dim>
typename stages::ParticleSource<dim>::Settings source_settings(const Vec<dim>& lo, const Vec<dim>& hi,
                                                               const Vec<dim>& v) {
  typename stages::ParticleSource<dim>::Settings s;
  s.lo = lo;
  s.hi = hi;
  s.velocity = v;
  s.dx = 0.1;
  s.particles_per_cell = dim == 2 ? 4 : 8;  // h = 0.05
  s.particle_volume = std::pow(0.05, dim);
  s.particle_mass = 1000.0 * s.particle_volume;
  return s;
}

//! Runs `source` for the steps `steps`, moving every particle by v dt in each.
template <int dim>
void stream(stages::ParticleSource<dim>& source, MpmState<dim>& s, const std::vector<double>& steps) {
  for (const double dt : steps) {
    s.dt = dt;
    source.run(s);
    for (std::size_t p = 0; p < s.particles.size(); ++p) s.particles.x[p] += dt * s.particles.v[p];
    s.time += dt;
  }
}

std::vector<double> uneven_steps(int n, double base) {
  std::vector<double> dt;
  for (int k = 0; k < n; ++k) dt.push_back(base * (0.3 + 0.7 * ((k * 7919) % 13) / 12.0));
  return dt;
}

template <int dim>
SceneSettings<dim> settings_of(const Config& scene) {
  return parse_scene_settings<dim>(scene);
}

const char* channel_yaml = R"(
dim: 2
domain: {lo: [0, -0.2], hi: [2, 1]}
grid: {dx: 0.1}
time: {end: 1}
walls: {contact: sticky}
)";

}  // namespace

TEST_CASE("erase_flagged removes flagged particles from every channel and keeps the order") {
  // Extra channels as a solid declares them (solid/solid_channels.h), without the solid library.
  Particles<3> P;
  std::vector<Mat<3>>& F = P.add_channel<Mat<3>>("F", Mat<3>::Identity(), {.output = true, .checkpoint = true});
  std::vector<double>& plastic = P.add_channel("plastic", 0.0, {.output = true, .checkpoint = true});
  for (int p = 0; p < 1000; ++p) {
    P.push_back(Vec<3>::Constant(p), Vec<3>::Constant(-p), 1.0 + p, 2.0 + p, static_cast<std::uint16_t>(p % 7));
    F.back() *= 1.0 + p;
    plastic.back() = 3.0 + p;
  }
  std::vector<std::uint8_t> none(P.size(), 0);
  CHECK(P.erase_flagged(none) == 0);
  CHECK(P.size() == 1000);

  std::vector<std::uint8_t> flagged(P.size(), 0);
  std::size_t expected = 0;
  for (int p = 0; p < 1000; ++p)
    if (p % 3 == 0 || p == 999 || (p > 500 && p < 520)) flagged[p] = 1, ++expected;
  CHECK(P.erase_flagged(flagged) == expected);
  REQUIRE(P.size() == 1000 - expected);
  P.for_each_channel([&](const ChannelInfo& info, const auto& values) {
    INFO(info.name);
    CHECK(values.size() == P.size());
  });
  int previous = -1;
  for (std::size_t i = 0; i < P.size(); ++i) {
    const int p = static_cast<int>(P.x[i][0]);
    CHECK(p > previous);  // stable
    CHECK(!flagged[p]);
    CHECK(P.v[i][2] == -p);
    CHECK(P.mass[i] == 1.0 + p);
    CHECK(P.volume0[i] == 2.0 + p);
    CHECK(P.material[i] == p % 7);
    CHECK(F[i](1, 1) == 1.0 + p);
    CHECK(plastic[i] == 3.0 + p);
    previous = p;
  }
  // Every particle of a set without extra channels can go.
  Particles<2> Q;
  for (int p = 0; p < 10; ++p) Q.push_back(Vec<2>::Constant(p), Vec<2>::Zero(), 1.0, 1.0, 0);
  CHECK(Q.erase_flagged(std::vector<std::uint8_t>(10, 1)) == 10);
  CHECK(Q.size() == 0);
  CHECK(Q.C.empty());
}

TEST_CASE("the source emits mass rho |v.n| A t to within one layer, on the moving lattice") {
  for (const double sign : {1.0, -1.0}) {
    CAPTURE(sign);
    // Face y in [0.2, 0.5): 6 lattice points, A = 0.3 m = 6 h.
    const auto settings = source_settings<2>(Vec<2>(0.1, 0.2), Vec<2>(0.3, 0.5), Vec<2>(sign * 0.7, 0.0));
    stages::ParticleSource<2> source(settings);
    CHECK(source.layer_size() == 6);
    MpmState<2> s;
    const std::vector<double> steps = uneven_steps(200, 0.04);
    stream(source, s, steps);
    const double rho = 1000.0, flux = 0.7 * 0.3, layer_mass = 6 * settings.particle_mass;
    const double t = s.time;
    CHECK(source.emitted_mass() == doctest::Approx(double(source.layers_by(t)) * layer_mass).epsilon(1e-15));
    double mass = 0.0;
    for (const double m : s.particles.mass) mass += m;
    CHECK(mass == doctest::Approx(source.emitted_mass()).epsilon(1e-14));
    CHECK(std::abs(source.emitted_mass() - rho * flux * t) <= layer_mass);
    CHECK(source.layers_by(t) > 50);

    // Advected at v, the emitted particles sit on the lattice moved by v_x t along x: layers
    // exactly h apart, none twice, none missing. Layer n started at x = c0 - sign n h, with the
    // first inner plane c0 = 0.125 (index 2) for sign > 0 and 0.275 (index 5) for sign < 0.
    std::vector<int> count(static_cast<std::size_t>(source.layers_by(t)) + 2, 0);
    for (const Vec<2>& x : s.particles.x) {
      const double index = (x[0] - sign * 0.7 * t) / 0.05 - 0.5;
      CHECK(std::abs(index - std::round(index)) < 1e-9);
      const double transverse = x[1] / 0.05 - 0.5;
      CHECK(std::abs(transverse - std::round(transverse)) < 1e-9);
      const int n = static_cast<int>(std::lround(sign > 0 ? 2.0 - index : index - 5.0));  // layer number
      REQUIRE(n >= 1);
      REQUIRE(n < static_cast<int>(count.size()));
      ++count[static_cast<std::size_t>(n)];
    }
    for (std::size_t n = 1; n <= static_cast<std::size_t>(source.layers_by(t)); ++n) CHECK(count[n] == 6);
  }
}

TEST_CASE("the number of layers depends on the time alone, and on start and stop") {
  auto settings = source_settings<3>(Vec<3>(0, 0, 0), Vec<3>(0.2, 0.2, 0.3), Vec<3>(0, 0, -1.3));
  settings.start = 0.05;
  settings.stop = 0.4;
  stages::ParticleSource<3> coarse(settings), fine(settings);
  CHECK(coarse.layer_size() == 16);
  MpmState<3> a, b;
  stream(coarse, a, std::vector<double>(25, 0.02));
  stream(fine, b, uneven_steps(300, 0.0025));
  REQUIRE(a.time > 0.4);
  REQUIRE(b.time > 0.4);
  CHECK(coarse.layers_by(0.049) == 0);
  CHECK(coarse.layers_by(0.4) == coarse.layers_by(10.0));
  // From start to stop: floor((1.3 * 0.35 + delta) / h) = floor(9.6) with delta = 0.025.
  CHECK(coarse.layers_by(a.time) == 9);
  CHECK(a.particles.size() == 9 * 16);
  CHECK(b.particles.size() == 9 * 16);
  CHECK(coarse.emitted_mass() == fine.emitted_mass());
  for (const Vec<3>& x : a.particles.x) CHECK(x[2] <= 0.3);
}

TEST_CASE("a source restarted from a saved state continues the same stream bit for bit") {
  const auto settings = source_settings<2>(Vec<2>(0, 0), Vec<2>(0.2, 0.2), Vec<2>(1.0, 0.3));
  const std::vector<double> steps = uneven_steps(100, 0.02);
  const std::vector<double> first(steps.begin(), steps.begin() + 37), rest(steps.begin() + 37, steps.end());
  stages::ParticleSource<2> continuous(settings), before(settings), after(settings);
  MpmState<2> a, b;
  stream(continuous, a, steps);
  stream(before, b, first);
  stream(after, b, rest);  // a new source on the saved state, as after a checkpoint
  REQUIRE(a.particles.size() == b.particles.size());
  CHECK(a.particles.size() == std::size_t(continuous.layers_by(a.time)) * continuous.layer_size());
  CHECK(a.particles.x == b.particles.x);
  CHECK(after.emitted_mass() == continuous.emitted_mass());
}

TEST_CASE("bad source settings are input errors") {
  auto settings = source_settings<2>(Vec<2>(0, 0), Vec<2>(0.2, 0.2), Vec<2>(0, 0));
  CHECK_THROWS_AS(stages::ParticleSource<2>{settings}, InputError);
  settings.velocity = Vec<2>(1, 0);
  settings.hi = Vec<2>(0.2, 0.01);  // the face holds no lattice point
  CHECK_THROWS_AS(stages::ParticleSource<2>{settings}, InputError);
  settings.hi = Vec<2>(0.2, 0.2);
  settings.stop = -1.0;
  CHECK_THROWS_AS(stages::ParticleSource<2>{settings}, InputError);
}

TEST_CASE("a stream through a sink keeps mass in = out + stored to round-off") {
  const Vec<2> lo(0, 0), hi(1, 0.5);
  auto settings = source_settings<2>(Vec<2>(0.1, 0.1), Vec<2>(0.3, 0.4), Vec<2>(0.9, 0.05));
  settings.particle_mass = 1000.0 * 0.0025 * 1.37;  // an inexact binary fraction
  stages::ParticleSource<2> source(settings);
  stages::ParticleSink<2> sink({stages::face_region<2>(lo, hi, 0, geometry::Side::upper, 0.2),
                                stages::SinkRegion<2>{Vec<2>(0.5, 0.3), Vec<2>(0.6, 0.35)}});
  MpmState<2> s;
  std::size_t grown = 0;
  for (const double dt : uneven_steps(400, 0.02)) {
    sink.run(s);
    // The source grows the particle storage to what the step needs or by a quarter, not by
    // doubling: a stream that levels off against a sink holds at most 5/4 of its count.
    const std::size_t before = s.particles.size(), room = s.particles.capacity();
    source.run(s);
    if (s.particles.capacity() != room) {
      ++grown;
      CHECK(s.particles.capacity() <= std::max(s.particles.size(), before + before / 4));
    }
    for (std::size_t p = 0; p < s.particles.size(); ++p) s.particles.x[p] += dt * s.particles.v[p];
    s.time += dt;
  }
  CHECK(grown > 2);
  sink.run(s);
  double stored = 0.0;
  for (const double m : s.particles.mass) stored += m;
  CHECK(sink.removed_count() > 300);
  CHECK(s.particles.size() > 50);
  CHECK(std::abs(source.emitted_mass() - sink.removed_mass() - stored) <= 1e-12 * source.emitted_mass());
  CHECK(sink.removed_mass() == doctest::Approx(double(sink.removed_count()) * settings.particle_mass).epsilon(1e-13));
  for (const Vec<2>& x : s.particles.x)
    for (const auto& region : sink.regions()) CHECK(!region.contains(x));
}

TEST_CASE("face regions hold the open layer of a face and everything beyond") {
  const Vec<2> lo(0, -1), hi(2, 1);
  const auto upper = stages::face_region<2>(lo, hi, 0, geometry::Side::upper, 0.2);
  CHECK(upper.contains(Vec<2>(1.8, 0.0)));
  CHECK(upper.contains(Vec<2>(5.0, -7.0)));
  CHECK(!upper.contains(Vec<2>(1.79, 0.0)));
  const auto lower = stages::face_region<2>(lo, hi, 1, geometry::Side::lower, 0.2);
  CHECK(lower.contains(Vec<2>(1.0, -1.5)));
  CHECK(!lower.contains(Vec<2>(1.0, -0.8)));  // half-open at the inner plane
  CHECK(lower.contains(Vec<2>(1.0, -0.81)));
}

TEST_CASE("inflow and outflow keys: open faces, a prescribed inlet, and rejected faces") {
  const std::string inflow =
      "inflow: {face: x_min, velocity: [0.5, 0.0], lo: [0, 0], hi: [0.4, 0.3], particles_per_cell: 4}\n";
  const Config scene = Config::parse(std::string(channel_yaml) + inflow + "outflow: {face: x_max}\n");
  const SceneSettings<2> settings = settings_of<2>(scene);
  auto colliders = geometry::parse_colliders<2>(scene, settings.domain_lo, settings.domain_hi, 0.2);
  const geometry::FlowBoundaries<2> flow = geometry::parse_flow_boundaries<2>(scene, settings);
  REQUIRE(flow.inflow);
  REQUIRE(flow.outflow);
  CHECK(geometry::face_name(*flow.outflow) == "x_max");
  geometry::add_flow_boundaries(flow, colliders);
  CHECK(!colliders.walls()->wall(0, geometry::Side::lower));
  CHECK(!colliders.walls()->wall(0, geometry::Side::upper));
  CHECK(colliders.walls()->wall(1, geometry::Side::lower));

  // Inlet nodes move at U whatever they held, at any time; the floor wall still wins below.
  Vec<2> v(-3.0, 2.0);
  colliders.project(Vec<2>(0.2, 0.1), 7.0, v);
  CHECK(v == Vec<2>(0.5, 0.0));
  v = Vec<2>(-3.0, 2.0);
  colliders.project(Vec<2>(0.2, -0.1), 7.0, v);
  CHECK(v == Vec<2>::Zero());
  v = Vec<2>(-3.0, 2.0);
  colliders.project(Vec<2>(1.95, 0.5), 7.0, v);  // open outflow face
  CHECK(v == Vec<2>(-3.0, 2.0));

  // The emitter enters half a lattice spacing past the open layer; the sinks cover both faces.
  const auto source = geometry::inflow_source(*flow.inflow, settings, 1000.0);
  CHECK(source.lo[0] == doctest::Approx(0.2 + 0.025));
  CHECK(source.particle_mass == doctest::Approx(1000.0 * 0.0025));
  const auto regions = geometry::flow_sink_regions(flow, settings);
  REQUIRE(regions.size() == 2);
  CHECK(regions[0].contains(Vec<2>(1.81, 0.1)));
  CHECK(regions[1].contains(Vec<2>(0.19, 0.1)));
  CHECK(!regions[1].contains(source.lo));
}

TEST_CASE("flow boundaries reject closed, shared or unreachable faces") {
  auto fails = [](const std::string& extra, const std::string& expected) {
    const Config scene = Config::parse(std::string(channel_yaml) + extra);
    const SceneSettings<2> settings = settings_of<2>(scene);
    CAPTURE(extra);
    try {
      geometry::parse_flow_boundaries<2>(scene, settings);
      FAIL("no error");
    } catch (const InputError& e) {
      CHECK(std::string(e.what()).find(expected) != std::string::npos);
      CAPTURE(e.what());
    }
  };
  const Config closed = Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.1}
time: {end: 1}
walls: {contact: sticky, x_max: slip}
outflow: {face: x_max}
)");
  try {
    geometry::parse_flow_boundaries<2>(closed, settings_of<2>(closed));
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("walls.x_max = slip") != std::string::npos);
  }
  const Config periodic = Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.1}
time: {end: 1}
periodic: [true, false]
walls: {contact: sticky, x_min: open, x_max: open}
outflow: {face: x_max}
)");
  try {
    geometry::parse_flow_boundaries<2>(periodic, settings_of<2>(periodic));
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("periodic axis") != std::string::npos);
  }
  fails("outflow: {face: w_max}\n", "expected one of x_min, x_max, y_min, y_max");
  fails("outflow: {face: x_min}\ninflow: {face: x_min, velocity: [1, 0], lo: [0, 0], hi: [0.5, 0.3]}\n",
        "also the outflow face");
  fails("inflow: {face: x_min, velocity: [-1, 0], lo: [0, 0], hi: [0.5, 0.3]}\n", "largest component is +x");
  fails("inflow: {face: x_min, velocity: [0.1, 0.5], lo: [0, 0], hi: [0.5, 0.3]}\n", "largest component is +x");
  fails("inflow: {face: x_min, velocity: [1, 0], lo: [0.3, 0], hi: [0.5, 0.3]}\n", "start within the open layer");
  fails("inflow: {face: x_min, velocity: [1, 0], lo: [0, 0], hi: [0.25, 0.3]}\n", "at least one cell");
  fails("inflow: {face: x_min, velocity: [1, 0], lo: [0, 0], hi: [0.5, 1.3]}\n", "inside the domain");
  fails("inflow: {face: x_min, velocity: [1, 0], lo: [0, 0], hi: [0.5, 0.01]}\n", "no point of the seeding lattice");
}
