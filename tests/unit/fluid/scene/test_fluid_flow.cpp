// Inflow and outflow in the fluid pipeline: the sink and source stages exist only in scenes
// with the keys, the inlet nodes keep the inflow velocity through the viscous solve and the
// pressure projection, and over many steps of a real channel the particle mass is exactly the
// initial mass plus what the source emitted minus what the sink removed.
#include <fluid/scene/fluid_scene.h>

#include <mpm/core/advance.h>
#include <mpm/core/stages/particle_sink.h>
#include <mpm/core/stages/particle_source.h>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>

using namespace mpm;

namespace {

const std::string channel = R"(
dim: 2
domain: {lo: [0, -0.04], hi: [0.6, 0.2]}
grid: {dx: 0.02}
time: {end: 1}
fluid: {density: 1000, viscosity: 1.0e-3}
pressure: {solver: cg, tolerance: 1.0e-10, max_iterations: 5000}
walls: {contact: sticky}
bodies:
  - {shape: box, lo: [0.04, 0], hi: [0.56, 0.08], velocity: [0.4, 0]}
)";

const std::string flow = R"(
inflow: {face: x_min, velocity: [0.4, 0], lo: [0, 0], hi: [0.08, 0.08]}
outflow: {face: x_max}
)";

}  // namespace

TEST_CASE("the sink and source stages exist only with inflow/outflow keys") {
  const Config plain = Config::parse(channel);
  const auto names = fluid::make_fluid_pipeline(fluid::load_fluid_scene<2>(plain)).stage_names();
  CHECK(std::find(names.begin(), names.end(), "sink") == names.end());
  CHECK(std::find(names.begin(), names.end(), "source") == names.end());

  const Config open = Config::parse(channel + flow);
  const auto with = fluid::make_fluid_pipeline(fluid::load_fluid_scene<2>(open)).stage_names();
  const std::vector<std::string> head(with.begin(), with.begin() + 4);
  CHECK(head == std::vector<std::string>{"time_step", "sink", "source", "sort"});
}

TEST_CASE("inlet nodes keep U through the projection; mass in = out + stored over a channel run") {
  const Config scene = Config::parse(channel + flow);
  fluid::FluidScene<2> water = fluid::load_fluid_scene<2>(scene);
  auto pipeline = fluid::make_fluid_pipeline(water);
  const auto* source = pipeline.find<stages::ParticleSource<2>>();
  const auto* sink = pipeline.find<stages::ParticleSink<2>>();
  REQUIRE(source);
  REQUIRE(sink);
  MpmState<2>& s = water.state;
  double initial = 0.0;
  for (const double m : s.particles.mass) initial += m;

  int inlet_nodes = 0;
  while (s.time < 1.0) {
    mpm::step_towards(s, pipeline, 1.0);
    // Inlet nodes above the floor's wall layer (y > 0) end the step at U exactly.
    for (std::size_t k = 0; k < s.grid.node_storage(); ++k) {
      const Vec<2> x = s.grid.node_position(k);
      if (s.grid.mass[k] <= 0.0 || x[0] > 0.08 || x[1] <= 1e-9 || x[1] > 0.08) continue;
      CHECK(s.grid.velocity[k] == Vec<2>(0.4, 0.0));
      ++inlet_nodes;
    }
  }
  double stored = 0.0;
  for (const double m : s.particles.mass) stored += m;
  CHECK(inlet_nodes > 100);
  CHECK(sink->removed_count() > 100);
  // rho U A t = 32 kg, within one layer of 8 particles of 0.1 kg.
  CHECK(std::abs(source->emitted_mass() - 1000.0 * 0.4 * 0.08 * 1.0) <= 0.8 + 1e-12);
  CHECK(std::abs(initial + source->emitted_mass() - sink->removed_mass() - stored) <= 1e-13 * stored);
}
