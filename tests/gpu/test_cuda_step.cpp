// The CUDA solid step against the CPU pipeline (label gpu). Run on a machine with a GPU; on one
// without, every case reports a skip and the program exits 77, which ctest shows as skipped.
//
// One 3D scene holds four bodies of the four device materials (fixed-corotated, Neo-Hookean,
// Drucker-Prager sand, von Mises goo) against the walls, a moving sphere, a box and a ramp;
// every particle starts from a random velocity, APIC C and F (|F - I| up to 0.3, enough to
// yield both plastic materials). After two steps, the device particles (x, v, C, F, plastic)
// must equal the CPU's to 1e-11 of each channel's scale in double and 1e-5 in single precision,
// also from shuffled storage, which the device moves into block order and maps back.
// No obstacle surface passes exactly through a node: there, phi = 0 up to round-off, and the two
// precisions may decide differently whether the node is inside.
// A free body (no obstacle reached) conserves momentum: sum m v after = before + dt M g.
#include <doctest/doctest.h>

#include <mpm/core/advance.h>
#include <mpm/cuda/device_pipeline.h>
#include <mpm/solid/solid_channels.h>
#include <mpm/solid/solid_scene.h>

#include "device_solid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

using namespace mpm;

namespace {

const char* kScene = R"(
dim: 3
domain: {lo: [0, 0, 0], hi: [1, 0.6, 0.6]}
grid: {dx: 0.04, kernel: quadratic}
materials:
  - {name: jello, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3, elasticity: fixed_corotated}
  - {name: rubber, density: 1200, youngs_modulus: 2.0e5, poisson_ratio: 0.4, elasticity: neo_hookean}
  - name: sand
    density: 2650
    youngs_modulus: 3.0e6
    poisson_ratio: 0.3
    elasticity: hencky_stvk
    plasticity: {model: drucker_prager, friction_angle: 32, cohesion: 200}
  - name: goo
    density: 1000
    youngs_modulus: 5.0e4
    poisson_ratio: 0.35
    elasticity: hencky_stvk
    plasticity: {model: von_mises, yield_stress: 300}
bodies:
  - {shape: box, lo: [0.08, 0.08, 0.08], hi: [0.28, 0.28, 0.28], material: jello, velocity: [-1, -1, 0]}
  - {shape: box, lo: [0.37, 0.10, 0.20], hi: [0.57, 0.30, 0.40], material: rubber, velocity: [1, 0, 0]}
  - {shape: box, lo: [0.66, 0.08, 0.30], hi: [0.90, 0.30, 0.52], material: sand}
  - {shape: sphere, center: [0.5, 0.45, 0.3], radius: 0.08, material: goo, velocity: [0, 1, 0]}
colliders:
  - {type: sphere, center: [0.5, 0.3, 0.42], radius: 0.06, velocity: [0, 0, -2], contact: separate, friction: 0.3}
  - {type: box, lo: [0.3, -0.1, -0.1], hi: [0.365, 0.13, 0.7], contact: sticky}
  - {type: half_space, point: [0.9, 0, 0], normal: [-1, 1, 0], contact: slip}
walls: {contact: separate, friction: 0.5, y_min: sticky}
time: {end: 1, frame_dt: 0.1, max_dt: 2.0e-4}
gravity: [0, -9.81, 0]
)";

const char* kFreeBody = R"(
dim: 3
domain: {lo: [0, 0, 0], hi: [1, 1, 1]}
grid: {dx: 0.05, kernel: quadratic}
materials:
  - name: sand
    density: 2650
    youngs_modulus: 3.0e6
    poisson_ratio: 0.3
    elasticity: hencky_stvk
    plasticity: {model: drucker_prager, friction_angle: 32}
bodies:
  - {shape: box, lo: [0.3, 0.3, 0.3], hi: [0.7, 0.7, 0.7], material: sand}
time: {end: 1, frame_dt: 0.1, max_dt: 2.0e-4}
gravity: [0, -9.81, 0]
)";

//! The same random state in every scene loaded from the same text. The channel "tag" holds each
//! particle's index: the CPU's sort moves particles, the device keeps the host's order.
solid::SolidScene<3> load(const char* text) {
  solid::SolidScene<3> s = solid::load_solid_scene<3>(Config::parse(text));
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles<3>& P = s.state.particles;
  auto& F = solid::elastic_F(P);
  auto& tag = P.add_channel<double>("tag", 0.0, {});
  for (std::size_t p = 0; p < P.size(); ++p) {
    tag[p] = double(p);
    for (int a = 0; a < 3; ++a) P.v[p][a] += 0.5 * u(random);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        P.C[p](r, c) = 5.0 * u(random);
        F[p](r, c) += 0.3 * u(random);
      }
  }
  return s;
}

//! Steps `scene` `steps` times to t = steps max_dt on the CPU or the device; the pipeline's
//! diagnostics after the last step.
std::vector<Diagnostic> run_steps(solid::SolidScene<3>& scene, const char* text, const cuda::Device& device,
                                  int steps = 1) {
  auto pipeline = cuda::make_solid_pipeline(scene, device, Config::parse(text));
  for (int s = 1; s <= steps; ++s) step_towards(scene.state, pipeline, s * scene.settings.max_dt);
  pipeline.synchronize(scene.state);
  return pipeline.diagnostics();
}

//! For every particle p of a, the index in b of the particle with the same tag.
std::vector<std::size_t> matching(const Particles<3>& a, const Particles<3>& b) {
  const std::vector<double>&ta = a.channel<double>("tag"), &tb = b.channel<double>("tag");
  std::vector<std::size_t> at_tag(tb.size()), where(ta.size());
  for (std::size_t q = 0; q < tb.size(); ++q) at_tag[static_cast<std::size_t>(tb[q])] = q;
  for (std::size_t p = 0; p < ta.size(); ++p) where[p] = at_tag[static_cast<std::size_t>(ta[p])];
  return where;
}

//! max_p |a_p - b_where[p]| / max_p |a_p| over the entries of a channel.
template <class Value>
double relative_difference(const std::vector<Value>& a, const std::vector<Value>& b,
                           const std::vector<std::size_t>& where) {
  double diff = 0.0, scale = 1e-300;
  for (std::size_t p = 0; p < a.size(); ++p) {
    const Value& other = b[where[p]];
    diff = std::max(diff, (Eigen::Map<const Eigen::VectorXd>(a[p].data(), a[p].size()) -
                           Eigen::Map<const Eigen::VectorXd>(other.data(), other.size()))
                              .cwiseAbs()
                              .maxCoeff());
    scale = std::max(scale, Eigen::Map<const Eigen::VectorXd>(a[p].data(), a[p].size()).cwiseAbs().maxCoeff());
  }
  return diff / scale;
}

double diagnostic(const std::vector<Diagnostic>& all, const std::string& name) {
  for (const Diagnostic& d : all)
    if (d.name == name) return d.value;
  return -1.0;
}

bool have_device() {
  const std::string why = cuda::unavailable_reason();
  if (!why.empty()) std::printf("SKIPPED: %s\n", why.c_str());
  return why.empty();
}

int skipped = 0;

}  // namespace

int cuda_cases_skipped() { return skipped; }

TEST_CASE("the device step equals the CPU step") {
  if (!have_device()) {
    ++skipped;
    return;
  }
  constexpr int kSteps = 2;
  solid::SolidScene<3> cpu = load(kScene);
  run_steps(cpu, kScene, {}, kSteps);
  for (const bool single : {false, true})
    for (const bool shuffled : {false, true}) {
      CAPTURE(single);
      CAPTURE(shuffled);
      solid::SolidScene<3> gpu = load(kScene);
      if (shuffled) {  // scattered storage: the device moves the data into block order and back
        std::vector<std::uint32_t> order(gpu.state.particles.size());
        std::iota(order.begin(), order.end(), 0u);
        std::shuffle(order.begin(), order.end(), std::mt19937_64(3));
        gpu.state.particles.permute(order);
      }
      const std::vector<Diagnostic> d = run_steps(gpu, kScene, {true, single}, kSteps);
      CHECK((diagnostic(d, "device_reorders") > 0) == shuffled);
      const double tolerance = single ? 1e-5 : 1e-11;
      const Particles<3>&a = cpu.state.particles, &b = gpu.state.particles;
      REQUIRE(a.size() == b.size());
      const std::vector<std::size_t> where = matching(a, b);
      const double dx = relative_difference(a.x, b.x, where), dv = relative_difference(a.v, b.v, where),
                   dC = relative_difference(a.C, b.C, where),
                   dF = relative_difference(solid::elastic_F(a), solid::elastic_F(b), where);
      std::printf("device %s%s vs CPU after %d steps (%zu particles): x %.2e  v %.2e  C %.2e  F %.2e\n",
                  single ? "single" : "double", shuffled ? ", shuffled" : "", kSteps, a.size(), dx, dv, dC, dF);
      CHECK(dx < tolerance);
      CHECK(dv < tolerance);
      CHECK(dC < tolerance);
      CHECK(dF < tolerance);
      double plastic = 0.0, scale = 1e-300;
      for (std::size_t p = 0; p < a.size(); ++p) {
        plastic = std::max(plastic, std::abs(solid::plastic_state(a)[p] - solid::plastic_state(b)[where[p]]));
        scale = std::max(scale, std::abs(solid::plastic_state(a)[p]));
      }
      CHECK(plastic / scale < 100 * tolerance);
    }
  // The steps must have done something: the random F yielded some sand to the apex.
  double stored = 0.0;
  for (const double v : solid::plastic_state(cpu.state.particles)) stored = std::max(stored, v);
  CHECK(stored > 0.0);
}

TEST_CASE("the device step conserves momentum") {
  if (!have_device()) {
    ++skipped;
    return;
  }
  for (const bool single : {false, true}) {
    CAPTURE(single);
    solid::SolidScene<3> s = load(kFreeBody);
    const Particles<3>& P = s.state.particles;
    Vec<3> before = Vec<3>::Zero();
    for (std::size_t p = 0; p < P.size(); ++p) before += P.mass[p] * P.v[p];
    run_steps(s, kFreeBody, {true, single});
    Vec<3> after = Vec<3>::Zero();
    double mass = 0.0, scale = 0.0;
    for (std::size_t p = 0; p < P.size(); ++p) {
      after += P.mass[p] * P.v[p];
      mass += P.mass[p];
      scale += P.mass[p] * P.v[p].norm();
    }
    const Vec<3> expected = before + s.settings.max_dt * mass * s.settings.gravity;
    const double error = (after - expected).norm() / scale;
    std::printf("device %s: momentum error %.2e of sum m |v|\n", single ? "single" : "double", error);
    CHECK(error < (single ? 1e-5 : 1e-12));
  }
}

TEST_CASE("device: cuda on a 2D scene or an unsupported feature is an input error") {
  const char* flat = R"(
dim: 2
domain: {lo: [0, 0], hi: [1, 1]}
grid: {dx: 0.1}
materials: [{name: m, density: 1000, youngs_modulus: 1.0e5, poisson_ratio: 0.3}]
bodies: [{shape: box, lo: [0.3, 0.3], hi: [0.6, 0.6], material: m}]
time: {end: 1, frame_dt: 0.1}
device: cuda
)";
  auto flat_scene = solid::load_solid_scene<2>(Config::parse(flat));
  CHECK_THROWS_AS(cuda::make_solid_pipeline(flat_scene, {true, false}, Config::parse(flat)), InputError);
  std::string cubic = kFreeBody;
  cubic.replace(cubic.find("quadratic"), 9, "cubic");
  auto cubic_scene = solid::load_solid_scene<3>(Config::parse(cubic));
  try {
    cuda::make_solid_pipeline(cubic_scene, {true, false}, Config::parse(cubic));
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("device") != std::string::npos);
  }
}

TEST_CASE("the warp-reduced P2G equals one shared atomic per particle") {
  // Particles crowded into one cell (more than a warp of peers: five rounds of the shuffle
  // tree), a shuffled lattice of 8 per cell (peers in scattered lanes) and a few lone particles
  // (blocks whose last warp is partly empty); two steps of sand and jelly in each scatter.
  if (!have_device()) {
    ++skipped;
    return;
  }
  namespace d = cuda::detail;
  d::DeviceScene scene{};
  for (int a = 0; a < 3; ++a) scene.origin[a] = 0.0, scene.node_counts[a] = 21, scene.gravity[a] = 0.0;
  scene.gravity[1] = -9.81;
  scene.dx = 0.05;
  scene.cfl = scene.wave_cfl = 0.5;
  scene.max_dt = 1e300;
  scene.materials = {{d::Elasticity::hencky_stvk, d::Plasticity::drucker_prager, 1.2e6, 1.7e6, 0.3, 0.0, 0.0},
                     {d::Elasticity::fixed_corotated, d::Plasticity::none, 4e4, 6e4, 0.0, 0.0, 0.0}};
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<std::array<double, 3>> x;
  for (int p = 0; p < 70; ++p) x.push_back({0.5 + 0.05 * u(random), 0.5 + 0.05 * u(random), 0.5 + 0.05 * u(random)});
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) x.push_back({0.3 + 0.025 * i, 0.2 + 0.025 * j, 0.25 + 0.025 * k});
  for (int p = 0; p < 7; ++p) x.push_back({0.85 + 0.02 * p, 0.85, 0.1 + 0.1 * p});
  std::shuffle(x.begin() + 70, x.end() - 7, random);
  d::HostParticles h;
  const std::size_t n = h.n = x.size();
  h.x.resize(3 * n), h.v.resize(3 * n), h.C.resize(9 * n), h.F.resize(9 * n);
  h.plastic.assign(n, 0.0), h.mass.assign(n, 0.02), h.volume0.assign(n, 1e-5), h.material.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    for (int a = 0; a < 3; ++a) h.x[a * n + p] = x[p][a], h.v[a * n + p] = u(random) - 0.5;
    for (int e = 0; e < 9; ++e) {
      h.C[e * n + p] = 4.0 * (u(random) - 0.5);
      h.F[e * n + p] = (e % 4 == 0 ? 1.0 : 0.0) + 0.2 * (u(random) - 0.5);
    }
    h.material[p] = static_cast<std::uint16_t>(p % 2);
  }
  for (const bool single : {false, true}) {
    CAPTURE(single);
    d::HostParticles out[2];
    for (const bool warp : {true, false}) {
      scene.p2g_scatter = warp ? d::DeviceScene::Scatter::warp_reduced : d::DeviceScene::Scatter::one_atomic;
      auto device = d::make_device_solid(scene, single);
      device->upload(h);
      device->step(1e-4, 1e-4);
      device->step(1e-4, 2e-4);
      device->download(out[warp]);
    }
    const auto difference = [&](const std::vector<double>& a, const std::vector<double>& b) {
      double diff = 0.0, scale = 1e-300;
      for (std::size_t i = 0; i < a.size(); ++i)
        diff = std::max(diff, std::abs(a[i] - b[i])), scale = std::max(scale, std::abs(a[i]));
      return diff / scale;
    };
    const double dx = difference(out[0].x, out[1].x), dv = difference(out[0].v, out[1].v),
                 dC = difference(out[0].C, out[1].C), dF = difference(out[0].F, out[1].F);
    std::printf("P2G %s, warp-reduced vs atomic after 2 steps (%zu particles): x %.2e  v %.2e  C %.2e  F %.2e\n",
                single ? "single" : "double", n, dx, dv, dC, dF);
    const double tolerance = single ? 1e-5 : 1e-12;
    CHECK(dx < tolerance);
    CHECK(dv < tolerance);
    CHECK(dC < tolerance);
    CHECK(dF < tolerance);
    // The two steps moved the particles: the comparison is not of untouched input.
    CHECK(difference(out[1].v, h.v) > 1e-3);
  }
}
