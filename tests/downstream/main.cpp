// Builds against the installed package and uses each exported target: a P2G of the core must
// conserve mass; the solid's explicit solver, libfluid's pressure settings and libcoupling's
// pipeline then settle a patch of sand in a tank of water for a few steps, which must keep the
// mass of each phase exactly and move the sand down.
#include <coupling/coupled_scene.h>
#include <fluid/scene/fluid_scene.h>
#include <mpm/core/advance.h>
#include <mpm/core/transfer.h>
#include <mpm/cuda/device_pipeline.h>
#include <mpm/geometry/collider_config.h>
#include <mpm/geometry/seeding.h>
#include <mpm/solid/solid_solver.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

bool core_p2g() {
  mpm::SparseGrid<2> grid(mpm::Vec<2>::Zero(), mpm::Vec<2>::Ones(), 0.1);
  mpm::Particles<2> particles;
  particles.push_back(mpm::Vec<2>(0.45, 0.52), mpm::Vec<2>(1.0, 0.0), 2.0, 1e-3, 0);
  mpm::ParticleBuckets<2> buckets;
  const mpm::Kernel kernel = mpm::QuadraticBSpline{};
  mpm::sort_into_buckets(particles, kernel, grid, buckets);
  mpm::particles_to_grid(particles, buckets, kernel, mpm::TransferScheme{}, grid);
  double mass = 0.0;
  for (double m : grid.mass) mass += m;
  std::printf("downstream: grid mass %.15g (expected 2)\n", mass);
  return std::fabs(mass - 2.0) < 1e-12;
}

bool coupled_step() {
  const mpm::Config cfg = mpm::Config::parse(R"(
dim: 2
domain: {lo: [0, 0], hi: [0.2, 0.2]}
grid: {dx: 0.01}
time: {end: 0.02}
)");
  const mpm::SceneSettings<2> settings = mpm::parse_scene_settings<2>(cfg);
  coupling::SedimentPhase<2> sand;
  sand.solver = mpm::solid::solid_solver_names().back();  // "grains"
  const coupling::drag::DragLaw law = coupling::drag::make_drag_law("stokes", {5e-4, 1e-3, 1000.0});
  auto walls = mpm::geometry::parse_colliders<2>(cfg, settings.domain_lo, settings.domain_hi,
                                                 mpm::wall_layer(settings.kernel, settings.dx));
  coupling::CoupledScene<2> scene = coupling::make_coupled_scene<2>(settings, walls, fluid::FluidMaterial{1000.0, 1e-3},
                                                                    fluid::stages::PressureSettings{}, sand, law);
  const double Vp = mpm::geometry::particle_volume<2>(settings.dx, 4), phi = 0.1;
  for (const mpm::Vec<2>& x :
       mpm::geometry::seed_box<2>(mpm::Vec<2>(0.03, 0.03), mpm::Vec<2>(0.17, 0.15), settings.dx, 4, 0.0, 1)) {
    const bool sandy = x[1] > 0.09;
    coupling::add_fluid_particles<2>(scene, {x}, Vp, sandy ? 1.0 - phi : 1.0, mpm::Vec<2>::Zero(), "water");
    if (sandy) coupling::add_sediment_particles<2>(scene, {x}, phi * Vp, mpm::Vec<2>::Zero(), "sand");
  }
  auto pipeline = coupling::make_coupled_pipeline(scene);
  coupling::CoupledState<2>& s = scene.state;
  const double water = s.fluid.particles.total_mass(), grains = s.sediment.particles.total_mass();
  mpm::advance(s, pipeline, 0.02);
  double sand_momentum = 0.0;
  for (std::size_t p = 0; p < s.sediment.particles.size(); ++p)
    sand_momentum += s.sediment.particles.mass[p] * s.sediment.particles.v[p][1];
  std::printf("downstream: %lld coupled steps, sand momentum %.6g kg m/s (expected < 0)\n",
              static_cast<long long>(s.step), sand_momentum);
  return s.fluid.particles.total_mass() == water && s.sediment.particles.total_mass() == grains && sand_momentum < 0.0;
}

}  // namespace

int main() {
  // mpm::cuda links with or without the CUDA back-end; without a GPU it says why.
  const std::string gpu = mpm::cuda::unavailable_reason();
  std::printf("downstream: CUDA back-end %s\n", gpu.empty() ? "ready" : gpu.c_str());
  const bool ok = core_p2g() && coupled_step();
  std::printf("downstream: %s\n", ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
