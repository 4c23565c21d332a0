// bench_cuda: the CUDA back-end of the solid step (mpm::cuda) on the benchmark of Gao et al.
// 2017 (sec. 8 "Benchmark.", Table 1; bench_transfer.cpp runs it on the CPU): particles on a
// lattice from 1/8 to 7/8 of the unit cube at spacing 1/256 (193^3 = 7.19 M particles),
// dx = 1/128, quadratic B-spline, APIC.
//
//   bench_cuda                          (the paper's sizes; needs a CUDA device)
//   bench_cuda --spacing 0.0078125 --steps 5
//
// 1. Transfers (P2G of mass and APIC momentum, G2P of v, C and x), per precision and input
//    order: "sorted" stores the particles in block order, "shuffled" in random order. Every
//    step bins the particles by a radix sort of (block key, index) pairs and allocates the
//    grid blocks they reach ("sort", part of each step's cost); scattered storage (shuffled
//    input) is moved into block order once, in its first step's "sort". Medians over --steps
//    steps of the device's event timings, and the first step.
// 2. The full explicit step of Drucker-Prager sand on the same particles (P2G with the stress,
//    grid update with walls, G2P with the deformation update, return map and stress; the time
//    step's reduction included): median wall-clock seconds per step.
#include "device_solid.h"

#include <mpm/core/error.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>
#include <string>
#include <vector>

using namespace mpm::cuda::detail;

namespace {

struct Options {
  double spacing = 1.0 / 256;
  double dx = 1.0 / 128;
  int steps = 10;
  std::string precision = "both";
  bool sand = true;
  std::string p2g = "both";  //!< warp, atomic or both (DeviceScene::p2g_scatter)
};

using Scatter = DeviceScene::Scatter;

//! The P2G scatters to run.
std::vector<Scatter> scatters(const Options& o) {
  if (o.p2g == "both") return {Scatter::warp_reduced, Scatter::one_atomic};
  return {o.p2g == "warp" ? Scatter::warp_reduced : Scatter::one_atomic};
}
const char* scatter_name(Scatter s) { return s == Scatter::warp_reduced ? "warp" : "atomic"; }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

HostParticles lattice(const Options& o, bool shuffled) {
  const int per_axis = static_cast<int>(std::lround(0.75 / o.spacing)) + 1;
  std::vector<std::array<double, 3>> x;
  x.reserve(std::size_t(per_axis) * per_axis * per_axis);
  for (int k = 0; k < per_axis; ++k)
    for (int j = 0; j < per_axis; ++j)
      for (int i = 0; i < per_axis; ++i)
        x.push_back({0.125 + i * o.spacing, 0.125 + j * o.spacing, 0.125 + k * o.spacing});
  // Sorted: by the block of the first stencil node (4^3 nodes), lexicographic as on the device.
  std::vector<long long> key(x.size());
  for (std::size_t p = 0; p < x.size(); ++p)
    for (int a = 2; a >= 0; --a) key[p] = key[p] * 4096 + static_cast<long long>(std::floor(x[p][a] / o.dx - 0.5)) / 4;
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  if (shuffled) std::shuffle(order.begin(), order.end(), std::mt19937_64(42));
  HostParticles h;
  const std::size_t n = h.n = x.size();
  h.x.resize(3 * n);
  h.v.resize(3 * n);
  h.C.assign(9 * n, 0.0);
  h.F.assign(9 * n, 0.0);
  h.plastic.assign(n, 0.0);
  h.mass.assign(n, 1000.0 * std::pow(o.spacing, 3));
  h.volume0.assign(n, std::pow(o.spacing, 3));
  h.material.assign(n, 0);
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (std::size_t p = 0; p < n; ++p) {
    for (int a = 0; a < 3; ++a) h.x[a * n + p] = x[order[p]][a], h.v[a * n + p] = u(random);
    for (int a = 0; a < 3; ++a) h.F[(4 * a) * n + p] = 1.0;
  }
  return h;
}

DeviceScene scene(const Options& o, bool transfers_only, Scatter scatter) {
  DeviceScene d{};
  const int nodes = static_cast<int>(std::lround(1.0 / o.dx)) + 1;
  for (int a = 0; a < 3; ++a) d.origin[a] = 0.0, d.node_counts[a] = nodes, d.gravity[a] = 0.0;
  d.dx = o.dx;
  d.cfl = 0.5;
  d.wave_cfl = 0.5;
  d.max_dt = 1e300;
  d.transfers_only = transfers_only;
  d.p2g_scatter = scatter;
  // Drucker-Prager sand (E = 3.5e7 Pa, nu = 0.3, 30 degrees; Gao et al.'s sand), Hencky elasticity.
  const double E = 3.5e7, nu = 0.3, mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double s = std::sin(30.0 * M_PI / 180.0);
  DeviceMaterial sand{Elasticity::hencky_stvk,
                      Plasticity::drucker_prager,
                      mu,
                      lambda,
                      std::sqrt(2.0 / 3.0) * 2.0 * s / (3.0 - s),
                      0.0,
                      0.0};
  d.materials = {sand};
  d.wave_speed = std::sqrt((lambda + 2 * mu) / 1000.0);
  if (!transfers_only) {
    d.gravity[1] = -9.81;
    d.walls.present = true;
    d.walls.layer = 2 * o.dx * (1 + 1e-9);
    for (int a = 0; a < 3; ++a) d.walls.hi[a] = 1.0;
    for (int f = 0; f < 6; ++f) d.walls.contact[f] = f == 2 ? 0 : 1;  // sticky floor, slip walls
  }
  return d;
}

//! Median phase times over `steps` steps after two warm-up steps; `first` gets the first step's.
struct Timing {
  StepTimes first, median;
};
Timing time_steps(DeviceSolid& device, int steps) {
  Timing r;
  std::vector<double> sort, p2g, grid, g2p;
  for (int s = 0; s < steps + 2; ++s) {
    device.step(1e-6, 1e-6 * (s + 1));
    const StepTimes t = device.last_times();
    if (s == 0) r.first = t;
    if (s < 2) continue;  // warm-up
    sort.push_back(t.sort), p2g.push_back(t.p2g), grid.push_back(t.grid), g2p.push_back(t.g2p);
  }
  r.median = {median(sort), median(p2g), median(grid), median(g2p)};
  return r;
}

double total(const StepTimes& t) { return t.sort + t.p2g + t.grid + t.g2p; }

void transfers(const Options& o, bool single, Scatter scatter) {
  const char* precision = single ? "single" : "double";
  for (const bool shuffled : {false, true}) {
    auto device = make_device_solid(scene(o, true, scatter), single);
    const HostParticles h = lattice(o, shuffled);
    device->upload(h);
    const Timing t = time_steps(*device, o.steps);
    const StepTimes& m = t.median;
    std::printf(
        "transfers %-6s %-8s %-6s %9zu particles  sort %7.3f ms  P2G %7.3f ms  grid %7.3f ms  G2P %7.3f ms  "
        "step %7.3f ms  (device memory %.2f GiB)\n",
        precision, shuffled ? "shuffled" : "sorted", scatter_name(scatter), h.n, 1e3 * m.sort, 1e3 * m.p2g,
        1e3 * m.grid, 1e3 * m.g2p, 1e3 * total(m), device->memory_bytes() / 1073741824.0);
    std::printf("transfers %-6s %-8s %-6s first step %7.3f ms (sort %.3f ms%s)\n", precision,
                shuffled ? "shuffled" : "sorted", scatter_name(scatter), 1e3 * total(t.first), 1e3 * t.first.sort,
                t.first.reordered ? ", the particle data moved into block order" : "");
  }
}

void sand_step(const Options& o, bool single, Scatter scatter) {
  auto device = make_device_solid(scene(o, false, scatter), single);
  const HostParticles h = lattice(o, false);
  device->upload(h);
  std::vector<double> wall, sort, p2g, grid, g2p;
  double t = 0.0;
  for (int s = 0; s < o.steps + 2; ++s) {
    const auto start = std::chrono::steady_clock::now();
    const double dt = device->stable_dt();
    device->step(dt, t + dt);
    const StepTimes times = device->last_times();  // waits for the step
    t += dt;
    if (s < 2) continue;
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    sort.push_back(times.sort), p2g.push_back(times.p2g), grid.push_back(times.grid), g2p.push_back(times.g2p);
  }
  std::printf(
      "sand step %-6s %-6s %9zu particles  wall %7.3f ms per step  (sort %.3f, P2G+stress %.3f, grid %.3f, "
      "G2P+F+return map %.3f ms)\n",
      single ? "single" : "double", scatter_name(scatter), h.n, 1e3 * median(wall), 1e3 * median(sort),
      1e3 * median(p2g), 1e3 * median(grid), 1e3 * median(g2p));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The CUDA solid step on Gao et al. 2017's Table 1 benchmark"};
  Options o;
  app.add_option("--spacing", o.spacing, "particle lattice spacing [m]");
  app.add_option("--dx", o.dx, "grid spacing [m]");
  app.add_option("--steps", o.steps, "timed steps per case");
  app.add_option("--precision", o.precision, "single, double or both")
      ->check(CLI::IsMember({"single", "double", "both"}));
  app.add_flag("!--no-sand", o.sand, "skip the full sand step");
  app.add_option("--p2g", o.p2g,
                 "P2G scatter: warp (reduced over the peers of a warp), atomic (one shared atomic per particle and "
                 "node) or both (DeviceScene::p2g_scatter says which the library takes)")
      ->check(CLI::IsMember({"warp", "atomic", "both"}));
  CLI11_PARSE(app, argc, argv);
  if (const std::string why = device_unavailable_reason(); !why.empty()) {
    std::fprintf(stderr, "bench_cuda: %s\n", why.c_str());
    return 77;
  }
  std::printf("bench_cuda on %s\n", device_description().c_str());
  try {
    for (const bool single : {true, false}) {
      if (o.precision != "both" && (o.precision == "single") != single) continue;
      for (const Scatter scatter : scatters(o)) {
        transfers(o, single, scatter);
        if (o.sand) sand_step(o, single, scatter);
      }
    }
  } catch (const mpm::Error& e) {
    std::fprintf(stderr, "bench_cuda: %s\n", e.what());
    return 1;
  }
  return 0;
}
